"""
Hardware in the loop without ROS: a candidate's trials on a test rig, and their scoring.

A rig evaluator evaluates a candidate as `core.evaluate` does, with each world's rollout
replaced by a trial on a rig. `RigTrials` is the protocol of one candidate, driven by events
and a clock: it asks for one trial per world (`TrialSpec`: the object's start pose, size,
mass, friction and how long to run), hears the rig say that the trial started (t = 0 of the
trial, in the clock of the poses) or collided at the start, collects the object's measured
poses and hears the trial end. Then it asks for the next world, or finishes:

- every world measured: each world's h_o from its pose trace with the schedule's own
  `Trace` (eq. 3 to 6, early termination included), their mean over the worlds plus eq. 2
  from the candidate's controller (eq. 5), in a core `Evaluation`;
- a start collision reported by the rig: every objective is COLLISION_PENALTY, as
  `core.evaluate` charges a design that starts in collision; no further trial is asked for;
- a trial that does not start or end in time, a rig that reports a failure, or a trace that
  lost tracking (no pose within `max_gap` of a check): the candidate is rejected with the
  reason, never scored.

The pose at a check time t (s from the trial's start) is defined from the measured samples:
a sample stamped within MATCH_TOLERANCE of t is taken as it is; otherwise the position is
interpolated linearly and the orientation by slerp between the samples just before and just
after t. A rig that publishes every physics step of the simulation therefore gives the
simulated evaluator's objectives exactly (the simulation reads the pose at the check steps).

Tolerance of a sampled trace: linear interpolation between samples h apart misses a smooth
motion by at most h^2 / 8 * max |p''| (the error term of linear interpolation), and slerp an
orientation by h^2 / 8 * max |angular acceleration| to first order. Each h_o is a mean of
per-check distances or angles, each moved by at most its check's interpolation error
(triangle inequality), so h_o, and the mean over worlds, moves by at most the largest
per-check error; eq. 2 does not depend on the trace. `interpolation_tolerance` estimates that
bound from the measured samples themselves (second differences: p(t - h) - 2 p(t) + p(t + h)
= h^2 p''; of the quaternions for orientations, a small turn by a moving one by a / 2), over
the samples around every check. Early termination can still switch at a
check whose pose is within the tolerance of a margin; the bound does not hold across that.
"""

import collections
from dataclasses import dataclass
from typing import Optional, Tuple

from hand_codesign.core.evaluate import Evaluation
from hand_codesign.core.run.evaluation_jobs import CandidateRejected, EvaluatorInbox
from hand_codesign.core.sim.objectives import (COLLISION_PENALTY, combine_worlds, goal_schedule,
                                               slerp, task_torque_penalty, weighted_fitness)
from hand_codesign.core.sim.worlds import object_state, world_states
from hand_codesign.core.task.genome import genome_spec
import numpy as np

MATCH_TOLERANCE = 1e-6  # s: a sample this close to a check time is the pose at that check
START_TIMEOUT = 30.0  # s of the evaluator's clock from a request to the rig's start
END_MARGIN = 30.0  # s of the evaluator's clock after the trial's duration before giving up
MAX_GAP = 0.1  # s between two samples around a check: more is lost tracking
SETTLE = 1.0  # s to wait after the end for poses still on their way (other topic)


class TrackingLost(Exception):
    """The measured trace has no usable pose at a check; the message says where."""


@dataclass(frozen=True)
class TrialSpec:
    """One trial to ask a rig for: a world of a candidate (the fields of a TrialRequest)."""

    world: int
    worlds: int
    shape: str
    size: Tuple[float, ...]
    scale: float
    position: Tuple[float, float, float]
    orientation: Tuple[float, float, float, float]
    mass: float
    friction: float
    duration: float


def trial_specs(task, worlds=None):
    """Return (ObjectState, TrialSpec) of every world of a task (None: the task's worlds)."""
    worlds = world_states(task) if worlds is None else list(worlds)
    duration = trial_duration(task)
    states = [object_state(task, world) for world in worlds]
    return [(state, TrialSpec(world=index, worlds=len(states), shape=task.object_spec.shape,
                              size=tuple(state.size), scale=float(state.scale),
                              position=tuple(state.position),
                              orientation=tuple(state.orientation), mass=float(state.mass),
                              friction=float(state.friction), duration=duration))
            for index, state in enumerate(states)]


def trial_duration(task):
    """Return how long a trial must run (s): to the last check that is scored."""
    schedule = goal_schedule(task)
    return float(schedule.check_times[-1]) if schedule.num_checks else float(task.duration)


def pose_at(times, positions, orientations, time, max_gap=MAX_GAP):
    """
    Return (position, orientation) at `time` from measured samples (see the module doc).

    times: increasing, s from the trial's start; raise TrackingLost without a usable pose.
    """
    index = int(np.searchsorted(times, time))
    for near in (index - 1, index):
        if 0 <= near < len(times) and abs(times[near] - time) <= MATCH_TOLERANCE:
            return tuple(positions[near]), tuple(orientations[near])
    if index == 0 or index == len(times):
        raise TrackingLost(f'no pose measured {"before" if index == 0 else "after"} '
                           f't = {time:.4f} s of the trial')
    before, after = times[index - 1], times[index]
    if after - before > max_gap:
        raise TrackingLost(f'tracking lost from t = {before:.4f} to {after:.4f} s of the '
                           f'trial ({after - before:.4f} s without a pose, at most '
                           f'{max_gap} s allowed)')
    fraction = (time - before) / (after - before)
    position = positions[index - 1] + fraction * (positions[index] - positions[index - 1])
    orientation = slerp(orientations[index - 1], orientations[index], fraction)
    return tuple(position), tuple(orientation)


def score_trace(schedule, state, times, positions, orientations, max_gap=MAX_GAP):
    """Return one world's h_o from a measured trace: eq. 3 to 6 with the schedule's Trace."""
    trace = schedule.new_trace(state)
    for time in schedule.check_times[:schedule.num_checks]:
        position, orientation = pose_at(times, positions, orientations, float(time), max_gap)
        if trace.record(position, orientation):
            break
    return trace.objective_values()


def interpolation_tolerance(schedule, times, positions, orientations):
    """
    Return (m, rad): the estimated interpolation error bound of a trace at the checks.

    h^2 / 8 * max |p''| with h^2 p'' estimated by the second differences of the three-sample
    windows around each check (module doc); 0 where a sample falls on the check.
    """
    worst = [0.0, 0.0]
    for time in schedule.check_times[:schedule.num_checks]:
        index = int(np.searchsorted(times, time))
        if any(0 <= near < len(times) and abs(times[near] - time) <= MATCH_TOLERANCE
               for near in (index - 1, index)):
            continue
        for first in range(max(index - 2, 0), min(index, len(times) - 2)):
            window = slice(first, first + 3)
            p = positions[window]
            worst[0] = max(worst[0], float(np.linalg.norm(p[0] - 2 * p[1] + p[2])) / 8)
            q = np.array(orientations[window], dtype=float)
            q[1:] *= np.sign(q[1:] @ q[0])[:, None] + (q[1:] @ q[0] == 0)[:, None]
            # a small turn by angle a moves a unit quaternion by a / 2
            worst[1] = max(worst[1], 2 * float(np.linalg.norm(q[0] - 2 * q[1] + q[2])) / 8)
    return tuple(worst)


@dataclass
class _Trial:
    spec: TrialSpec
    state: object
    trial_id: int
    requested: float
    start_ns: Optional[int] = None
    end_ns: Optional[int] = None
    ended_at: Optional[float] = None
    samples: list = None


class RigTrials:
    """
    The trials of one candidate, one world after another (see the module doc).

    Feed it `started`, `collided`, `failed`, `pose` and `ended` as the rig reports them and
    call `poll(now)`: it returns ('request', trial id, TrialSpec), ('evaluated', Evaluation
    and the measured traces), ('rejected', reason) or None while it waits.
    """

    def __init__(self, task, design, worlds=None, first_trial_id=0, start_timeout=START_TIMEOUT,
                 end_margin=END_MARGIN, max_gap=MAX_GAP, settle=SETTLE):
        self.task = task
        self.schedule = goal_schedule(task)
        self.penalty = task_torque_penalty(
            task, design.controller.values if task.policy.kind == 'torque' else ())
        self.specs = trial_specs(task, worlds)
        self.next_id = first_trial_id
        self.start_timeout, self.end_margin = start_timeout, end_margin
        self.max_gap, self.settle = max_gap, settle
        self.trial = None
        self.values = []   # h_o of the worlds measured so far
        self.traces = []   # (times, positions, orientations) of each measured world
        self.outcome = None

    # ---- what the rig reports (events of other trials are ignored)

    def _current(self, trial_id):
        return self.trial is not None and self.trial.trial_id == trial_id

    def started(self, trial_id, stamp_ns):
        """Take the rig's start of the trial: t = 0 at stamp_ns (the clock of its poses)."""
        if self._current(trial_id) and self.trial.start_ns is None:
            self.trial.start_ns = int(stamp_ns)

    def collided(self, trial_id):
        """Take a start collision: every objective is the collision penalty."""
        if self._current(trial_id) and self.outcome is None:
            values = np.full((len(self.specs), self.schedule.num_objectives),
                             COLLISION_PENALTY)
            self.outcome = ('evaluated', self._evaluation(values, True), self.traces)

    def failed(self, trial_id, reason):
        """Take the rig's report that it could not run the trial."""
        if self._current(trial_id) and self.outcome is None:
            self._reject(f'the rig failed: {reason or "no reason given"}')

    def pose(self, stamp_ns, position, orientation):
        """Take a measured pose of the object, stamped in the rig's clock (may come first)."""
        if self.trial is not None:
            self.trial.samples.append((int(stamp_ns), tuple(position), tuple(orientation)))

    def ended(self, trial_id, stamp_ns, now):
        """Take the trial's end at stamp_ns; its last poses may still be on their way."""
        if self._current(trial_id) and self.trial.start_ns is not None:
            self.trial.end_ns, self.trial.ended_at = int(stamp_ns), now

    # ---- the protocol

    def poll(self, now):
        """Return what to do now (see the class doc); the outcome repeats once reached."""
        if self.outcome is not None:
            return self.outcome
        trial = self.trial
        if trial is None:
            return self._request(now)
        if trial.start_ns is None:
            if now - trial.requested > self.start_timeout:
                self._reject(f'timeout: the rig did not start trial {trial.trial_id} (world '
                             f'{trial.spec.world}) within {self.start_timeout} s')
            return self.outcome
        if trial.end_ns is None:
            if now - trial.requested > self.start_timeout + trial.spec.duration + \
                    self.end_margin:
                self._reject(f'timeout: trial {trial.trial_id} (world {trial.spec.world}) did '
                             'not end in time')
            return self.outcome
        latest = max((sample[0] for sample in trial.samples), default=-1)
        if latest < trial.end_ns and now - trial.ended_at < self.settle:
            return None   # the last poses travel on another topic than the end
        self._score(trial)
        return self.outcome if self.outcome is not None else self._request(now)

    def _request(self, now):
        state, spec = self.specs[len(self.values)]
        self.trial = _Trial(spec, state, self.next_id, now, samples=[])
        self.next_id += 1
        return ('request', self.trial.trial_id, spec)

    def _score(self, trial):
        samples = sorted(sample for sample in trial.samples
                         if trial.start_ns <= sample[0] <= trial.end_ns)
        times = np.array([(stamp - trial.start_ns) * 1e-9 for stamp, _, _ in samples])
        positions = np.array([sample[1] for sample in samples]).reshape(-1, 3)
        orientations = np.array([sample[2] for sample in samples]).reshape(-1, 4)
        try:
            values = score_trace(self.schedule, trial.state, times, positions, orientations,
                                 self.max_gap)
        except TrackingLost as lost:
            self._reject(f'world {trial.spec.world}: {lost}')
            return
        self.values.append(values)
        self.traces.append((times, positions, orientations))
        self.trial = None
        if len(self.values) == len(self.specs):
            world_values = np.array(self.values)
            self.outcome = ('evaluated', self._evaluation(world_values, False), self.traces)

    def _reject(self, reason):
        self.outcome = ('rejected', reason)

    def _evaluation(self, world_values, collision):
        task = self.task
        objectives = combine_worlds(world_values, self.penalty, collision,
                                    task.worlds.worst_fraction)
        empty = np.zeros((len(self.specs), 2))
        measured = sum(float(times[-1]) for times, _, _ in self.traces if len(times))
        return Evaluation(objectives=np.asarray(objectives, dtype=float),
                          objective_names=tuple(task.objective_names),
                          fitness=weighted_fitness(objectives, task.objective_weights),
                          world_objectives=world_values, collision=bool(collision),
                          unstable_worlds=0, simulated_time=measured,
                          initial_errors=empty, final_errors=empty.copy(),
                          final_poses=np.zeros((len(self.specs), 7)))


class RigEvaluator:
    """
    A rig evaluator's decisions without ROS: which candidates, and the trials of each in turn.

    Candidates are taken by the EvaluatorInbox rules of every evaluator and evaluated one
    after another (a rig runs one trial at a time). Feed it messages (`run_announced`,
    `candidate_arrived`, the rig's `started` / `collided` / `failed` / `ended` and `pose`)
    and call `poll(now)`, which returns actions: ('request', candidate, trial id, TrialSpec),
    ('evaluated', candidate, Evaluation, wall seconds) or ('rejected', candidate, reason).
    """

    def __init__(self, evaluator_id, wanted_run='', credential=None, **limits):
        self.inbox = EvaluatorInbox(evaluator_id, wanted_run, credential=credential)
        self.limits = limits  # start_timeout, end_margin, max_gap, settle of RigTrials
        self.queue = collections.deque()
        self.current = None  # (candidate, RigTrials, started at)
        self.next_trial_id = 1
        self.done = 0

    def run_announced(self, run):
        """Take a RunInfo (and the candidates that waited for it)."""
        self.queue.extend(self.inbox.run_announced(run))

    def candidate_arrived(self, candidate):
        """Queue a candidate if it is for this evaluator."""
        self.queue.extend(self.inbox.candidate_arrived(candidate))

    def load(self):
        """Return the candidates taken and not answered yet."""
        return len(self.queue) + (self.current is not None)

    def _trials(self):
        return None if self.current is None else self.current[1]

    def started(self, trial_id, stamp_ns):
        """Forward the rig's start of a trial to the candidate in progress."""
        if self._trials():
            self._trials().started(trial_id, stamp_ns)

    def collided(self, trial_id):
        """Forward a start collision."""
        if self._trials():
            self._trials().collided(trial_id)

    def failed(self, trial_id, reason):
        """Forward a failed trial."""
        if self._trials():
            self._trials().failed(trial_id, reason)

    def ended(self, trial_id, stamp_ns, now):
        """Forward the end of a trial."""
        if self._trials():
            self._trials().ended(trial_id, stamp_ns, now)

    def pose(self, stamp_ns, position, orientation):
        """Forward a measured pose."""
        if self._trials():
            self._trials().pose(stamp_ns, position, orientation)

    def poll(self, now):
        """Return the actions due now (see the class doc)."""
        actions = [('rejected', candidate, f'no RunInfo received for run "{candidate.run_id}"')
                   for candidate in self.inbox.orphans()]
        while self.current is None and self.queue:
            candidate = self.queue.popleft()
            try:
                job = self.inbox.job(candidate)
                design = genome_spec(job.task).decode(job.genome)
            except CandidateRejected as reason:
                actions.append(('rejected', candidate, str(reason)))
                continue
            trials = RigTrials(job.task, design, job.worlds, self.next_trial_id, **self.limits)
            self.current = (candidate, trials, now)
        if self.current is None:
            return actions
        candidate, trials, since = self.current
        action = trials.poll(now)
        if action is None:
            return actions
        if action[0] == 'request':
            self.next_trial_id = trials.next_id
            return actions + [('request', candidate, action[1], action[2])]
        self.current = None
        self.done += 1
        if action[0] == 'evaluated':
            return actions + [('evaluated', candidate, action[1], now - since)]
        return actions + [('rejected', candidate, action[1])]
