"""
Objectives of section III.C in plain numpy: equations (2) to (6).

Objective o is one goal i of the task: `position_i` or `orientation_i`. A single-goal
objective scores the object's pose at the goal's time; a trajectory objective also scores
interpolated goals (positions linearly, orientations by slerp) from the previous goal (goal 0
is the object's nominal start pose at t = 0) at every multiple of 1 / goals.samples_per_second
(default 0.1 s, the early-termination checks) strictly between the two goal times, and at the
goal's own time. h_o is the mean of these scores (eq. 5, inner sum).

`GoalSchedule` precomputes all of that once per task: the steps at which the rollout loop
must read the object pose ("checks"), the target of every goal sample and which checks are
early-termination checks. The rollout loop only compares its step counter with the next check
step and calls `Trace.record` there, so nothing is allocated per physics step::

    schedule = goal_schedule(task)
    trace = schedule.new_trace()
    next_check = schedule.check_step_list[0]
    for step in range(1, schedule.num_steps + 1):
        ...                                   # apply torques, step the physics
        if step == next_check:
            position, orientation = client.getBasePositionAndOrientation(body)
            if trace.record(position, orientation):   # True: early termination
                break
            next_check = schedule.next_check_step(trace.count)
    values = trace.objective_values()        # h_o (eq. 5) or h'_o (eq. 6) of this world

Steps count from 1: the state after step s is the state at time s * time_step.

Goals relative to the start (goals.relative_to_start): each world's goal is the nominal goal
carried along by that world's start, so every goal asks for the same world-frame motion from
the start in every world: positions shifted by the start's displacement, orientations
q_goal * q_nominal^-1 * q_start (the same world-frame turn R = q_goal * q_nominal^-1, applied
to the world's own start). The schedule holds the goals of the nominal start; `new_trace(start)`
and `pose_errors(..., start)` take the world's ObjectState and map every measured pose into the
nominal start's frame instead (position minus the offset, orientation q * q_start^-1 * q_nominal):
a rotation angle between two quaternions is unchanged when both are multiplied on the right by
the same unit quaternion, so that scores exactly as against the world's own goals, which
`world_goal(..., start)` returns for display (`hand-codesign check`). Without the option
`start` is ignored.

Position goals measure the world axes they name (`axes`, e.g. [x, y] for an object on the
plane): eq. (3) over those coordinates only, in the samples, early termination and
`pose_errors` alike. With `goals.orientation_symmetry` the object looks the same turned by
k * 2 pi / order about its own axis: `Trace.record` keeps, of those turns of the measured
orientation, the one nearest to the check's orientation target (its last goal's when the check
has none), so every orientation error below is eq. (4) to the nearest symmetric turn. The turns
are about the object's own axis, so in a world whose measured poses map to the nominal start
(q * turn) they are conjugated by that world's turn.

Early termination (eq. 6): with `early_termination` set, at every multiple of
1 / checks_per_second (10 per simulated second) the goal samples of that step are compared with
their margins s_o (d_s for positions, theta_s for orientations); if one misses by more, the
rollout stops at t_stop. An objective whose goal time T(o) <= t_stop keeps h_o. Otherwise the
samples scored up to and including t_stop are summed and the not evaluated ones are charged
s_o each, counted by the proportion a_o = (T(o) - t_stop) / (T(o) - t(o)) of the objective's
|o| samples: h'_o = (a_o |o| s_o + sum) / |o|. For a single goal (|o| = 1) this is the
paper's formula as printed; for a trajectory, reading the charge as a_o s_o / |o| instead
would make stopping early cheaper than finishing, so the proportion counts samples. When the
rollout stops before an objective's window, a_o > 1: stopping earlier costs more.

A horizon (task.horizon, set per candidate by the search: hand_codesign.core.search.horizon) keeps
only the checks up to it and stops at none of them: the rollout ends at the last check at or
before the horizon and is scored as eq. (6) with t_stop there. At or beyond the last goal it is
the whole rollout, scored by eq. (5).
"""

import math
from typing import Optional

from hand_codesign.core.rotations import (axis_angle_quaternion, quaternion_conjugate,
                                          quaternion_multiply, slerp)
from hand_codesign.core.task import Task, TaskError
import numpy as np

COLLISION_PENALTY = 10000.0  # every objective of a design that starts in collision (eq. 5)


def torque_penalty(torques, threshold, weight):
    """Return eq. (2): weight * (max |torque| - threshold) if that max exceeds threshold."""
    torques = np.asarray(torques, dtype=float)
    if torques.size == 0:
        return 0.0
    peak = float(np.max(np.abs(torques)))
    return weight * (peak - threshold) if peak > threshold else 0.0


def task_torque_penalty(task: Task, torques):
    """Return eq. (2) with the task's tau_p and w (0 when the task sets no penalty)."""
    spec = task.torque_penalty
    return 0.0 if spec is None else torque_penalty(torques, spec.threshold, spec.weight)


def design_torque_penalty(task: Task, design):
    """Return eq. (2) of a Design on `task`: its torque values', 0 for a PD policy."""
    return task_torque_penalty(task, design.controller.values
                               if task.policy.kind == 'torque' else ())


def position_distance(actual, desired, metric='euclidean', mask=None):
    """
    Return eq. (3): the Euclidean or Manhattan distance over the last axis.

    `mask` (1 for a measured axis, 0 for an ignored one; default all measured) restricts it
    to a position goal's `axes`.
    """
    difference = np.asarray(actual, dtype=float) - np.asarray(desired, dtype=float)
    if mask is not None:
        difference = difference * mask
    if metric == 'manhattan':
        return np.sum(np.abs(difference), axis=-1)
    return np.sqrt(np.sum(difference * difference, axis=-1))


def orientation_angle(actual, desired):
    """
    Return eq. (4): the rotation angle arccos(2 <q, q_d>^2 - 1) between unit quaternions.

    In [0, pi]; q and -q give the same angle. The argument is clipped to [-1, 1] so rounding
    never yields NaN.
    """
    inner = np.sum(np.asarray(actual, dtype=float) * np.asarray(desired, dtype=float),
                   axis=-1)
    return np.arccos(np.clip(2.0 * inner * inner - 1.0, -1.0, 1.0))


def combine_worlds(world_values, penalty=0.0, collision=False, fraction=1.0):
    """
    Return eq. (5): the objective vector from per-world h_o values (worlds x objectives).

    Every objective is COLLISION_PENALTY for a design that starts in collision, otherwise
    the torque penalty plus the mean over the worlds, or with `fraction` < 1 (the task's
    worlds.aggregate: worst) plus `worst_mean`, the mean over the worst `fraction` of them.
    """
    world_values = np.asarray(world_values, dtype=float)
    if collision:
        return np.full(world_values.shape[-1], COLLISION_PENALTY)
    if fraction >= 1.0:
        return penalty + world_values.mean(axis=0)
    return penalty + worst_mean(world_values, fraction)


def worst_mean(world_values, fraction):
    """
    Return per objective the mean over the worst `fraction` of the worlds: CVaR at 1 - fraction.

    Rockafellar and Uryasev (2000, "Optimization of conditional value-at-risk", J. Risk 2(3))
    define the conditional value at risk of a loss as its mean in the upper tail of
    probability `fraction`; for n equally likely worlds that tail holds k = fraction * n
    worlds: the floor(k) worst in full and the next worst with the weight k - floor(k), all
    divided by k (Rockafellar and Uryasev 2002, J. Banking & Finance 26, for discrete
    distributions). It is continuous in `fraction`, is the mean at 1 and the worst world as
    fraction * n approaches 1 (at or below it). Each objective takes its own worst worlds. As a
    robust-design objective it is the risk-averse middle between the mean (the paper's
    eq. 5) and the worst case of min-max robust optimization (Ben-Tal, El Ghaoui and
    Nemirovski 2009, Robust Optimization).
    """
    world_values = np.asarray(world_values, dtype=float)
    count = world_values.shape[0]
    tail = float(fraction) * count
    if abs(tail - round(tail)) < 1e-9:  # 0.1 * 30 is 3.0000000000000004
        tail = float(round(tail))
    tail = min(max(tail, 1e-12), float(count))
    whole = int(np.floor(tail))
    weights = np.zeros(count)
    weights[:whole] = 1.0
    if whole < count:
        weights[whole] = tail - whole
    descending = -np.sort(-world_values, axis=0)
    return weights @ descending / tail


def weighted_fitness(objectives, weights):
    """Return the weighted sum that single-objective CMA-ES minimizes."""
    return float(np.dot(np.asarray(objectives, dtype=float), np.asarray(weights, dtype=float)))


class GoalSchedule:
    """
    When the rollout reads the object pose, and what each reading is scored against.

    Attributes (all read-only): num_steps; check_steps (int array, increasing, >= 1) and
    check_step_list (the same as Python ints, for the loop); check_times (s); termination
    (bool per check: an early-termination check); num_objectives, objective_names;
    objective_start_times t(o), objective_end_times T(o), objective_sizes |o|; margins
    (s_o per objective, or None without early termination); last_position and
    last_orientation (the final goals, or the start pose for a kind without goals, which
    pose_errors scores 0).
    """

    def __init__(self, task: Task):
        self.task_source = task.source
        self.time_step = task.time_step
        self.num_steps = task.num_steps
        self.distance = task.goals.distance
        self.objective_names = tuple(task.objective_names)
        start = task.object_spec
        position_samples = self._samples(task, 'position', np.array(start.position))
        orientation_samples = self._samples(task, 'orientation',
                                            np.array(start.orientation))
        steps = sorted({step for samples in position_samples + orientation_samples
                        for step, _ in samples[2]})
        self.check_steps = np.array(steps, dtype=int)
        self.check_step_list = tuple(int(step) for step in steps)
        self.check_times = self.check_steps * self.time_step
        check_of_step = {step: index for index, step in enumerate(steps)}
        self.num_checks = len(steps)
        self.num_position = len(position_samples)
        self.num_objectives = self.num_position + len(orientation_samples)
        windows = [(s[0], s[1], len(s[2])) for s in position_samples + orientation_samples]
        self.objective_start_times = np.array([w[0] for w in windows]) * self.time_step
        self.objective_end_times = np.array([w[1] for w in windows]) * self.time_step
        self.objective_sizes = np.array([w[2] for w in windows], dtype=float)
        self._position = self._table(position_samples, check_of_step, 3, 0)
        masks = [_axes_mask(goal.axes) for goal in task.goals.position]
        self._position['mask'] = (np.array([masks[row] for row in self._position['objective']])
                                  if masks else np.zeros((0, 3)))
        self._orientation = self._table(orientation_samples, check_of_step, 4,
                                        self.num_position)
        self.termination = np.zeros(self.num_checks, dtype=bool)
        self.margins = None
        early = task.early_termination
        if early is not None:
            self.position_margin = early.distance
            self.orientation_margin = early.angle
            self.margins = np.array([early.distance] * self.num_position
                                    + [early.angle] * len(orientation_samples))
            interval = 1.0 / early.checks_per_second
            count = int(math.floor(task.duration / interval + 1e-9))
            termination_steps = {int(round(k * interval / self.time_step))
                                 for k in range(1, count + 1)}
            self.termination = np.array([step in termination_steps for step in steps],
                                        dtype=bool)
        self._termination_list = tuple(bool(flag) for flag in self.termination)
        self.last_position = np.array(task.goals.position[-1].position
                                      if task.goals.position else start.position)
        self.last_orientation = np.array(task.goals.orientation[-1].orientation
                                         if task.goals.orientation else start.orientation)
        # pose_errors measures the last position goal's axes; none for a task without one
        self.last_mask = (_axes_mask(task.goals.position[-1].axes) if task.goals.position
                          else np.zeros(3))
        self.has_orientation_goals = bool(task.goals.orientation)
        self.symmetries = _symmetry_turns(task.goals.orientation_symmetry)
        self.relative_to_start = task.goals.relative_to_start
        self.start_position = np.array(start.position, dtype=float)
        self.start_orientation = tuple(start.orientation)
        self.all_checks = self.num_checks
        self.horizon = None
        if task.horizon is not None:
            self._limit_to(task.horizon)

    def _limit_to(self, horizon):
        """
        Keep the checks up to `horizon` (s) and stop nowhere before it (see horizon.py).

        The rollout ends at the last check at or before the horizon and is scored as if early
        termination had stopped it there: eq. (6) with t_stop = that check.
        """
        if self.margins is None:
            raise TaskError(f'{self.task_source}: a horizon ({horizon} s) needs '
                            'early_termination (its margins charge the goals after it)')
        kept = int(np.searchsorted(self.check_times, horizon + 1e-9, side='right'))
        if kept == 0:
            raise TaskError(f'{self.task_source}: horizon {horizon} s ends before the first '
                            f'check at {self.check_times[0]} s')
        self.horizon = float(horizon)
        self.num_checks = kept
        self.check_steps = self.check_steps[:kept]
        self.check_step_list = self.check_step_list[:kept]
        self.check_times = self.check_times[:kept]
        self.termination = np.zeros(kept, dtype=bool)
        self._termination_list = (False,) * kept

    # ---- building

    def _samples(self, task, kind, start_target):
        """Return per goal: (start step, end step, [(step, target), ...])."""
        goals = getattr(task.goals, kind)
        rate = task.goals.samples_per_second
        result = []
        previous_step, previous_target = 0, start_target
        for index, goal in enumerate(goals):
            target = np.array(getattr(goal, kind), dtype=float)
            end_step = int(round(goal.time / self.time_step))
            if end_step <= previous_step:
                raise TaskError(f'{task.source}: goals.{kind}[{index}].time: expected at '
                                f'least one time step ({self.time_step} s) after the previous '
                                f'goal, got {goal.time!r}')
            steps = [end_step]
            if goal.trajectory:
                first = int(math.floor(previous_step * self.time_step * rate + 1e-9)) + 1
                last = int(math.ceil(end_step * self.time_step * rate - 1e-9)) - 1
                grid = {int(round(k / rate / self.time_step)) for k in range(first, last + 1)}
                steps = sorted(s for s in grid if previous_step < s < end_step) + steps
            samples = []
            for step in steps:
                fraction = (step - previous_step) / (end_step - previous_step)
                if kind == 'position':
                    value = previous_target + fraction * (target - previous_target)
                else:
                    value = slerp(previous_target, target, fraction)
                samples.append((step, value))
            result.append((previous_step, end_step, samples))
            previous_step, previous_target = end_step, target
        return result

    def _table(self, samples, check_of_step, width, first_objective):
        """Return sample arrays sorted by check, with each check's [start, end) slice."""
        rows = [(check_of_step[step], first_objective + objective, target)
                for objective, (_, _, entries) in enumerate(samples)
                for step, target in entries]
        rows.sort(key=lambda row: (row[0], row[1]))
        checks = np.array([row[0] for row in rows], dtype=int)
        table = {
            'check': checks,
            'objective': np.array([row[1] for row in rows], dtype=int),
            'target': (np.array([row[2] for row in rows]) if rows
                       else np.zeros((0, width))),
            'start': np.searchsorted(checks, np.arange(self.num_checks), side='left'),
            'end': np.searchsorted(checks, np.arange(self.num_checks), side='right'),
        }
        table['start_list'] = tuple(int(v) for v in table['start'])
        table['end_list'] = tuple(int(v) for v in table['end'])
        return table

    def goal_samples(self):
        """Return (objective name, time, target) of every goal sample (up to the horizon)."""
        samples = []
        for table in (self._position, self._orientation):
            for check, objective, target in zip(table['check'], table['objective'],
                                                table['target']):
                if check >= self.num_checks:
                    continue
                samples.append((self.objective_names[objective],
                                float(self.check_times[check]), target.copy()))
        samples.sort(key=lambda sample: (sample[1], self.objective_names.index(sample[0])))
        return samples

    # ---- the rollout side

    def new_trace(self, start=None):
        """Return an empty Trace (preallocated) for one rollout from `start` (ObjectState)."""
        return Trace(self, self.start_transform(start))

    def start_transform(self, start):
        """
        Return (offset, turn) mapping a world's poses to the nominal start, or None.

        A measured pose (p, q) of the world maps to (p - offset, q * turn). None when goals
        are absolute or no start is given.
        """
        if not self.relative_to_start or start is None:
            return None
        offset = np.asarray(start.position, dtype=float) - self.start_position
        turn = quaternion_multiply(quaternion_conjugate(start.orientation),
                                   self.start_orientation)
        return offset, turn

    def world_goal(self, position, orientation, start=None):
        """
        Return a nominal goal (position or None, orientation or None) in the world of `start`.

        The inverse of the mapping of `start_transform`: p + offset, q * turn^-1, which is
        q_goal * q_nominal^-1 * q_start.
        """
        transform = self.start_transform(start)
        if transform is None:
            return position, orientation
        offset, turn = transform
        if position is not None:
            position = np.asarray(position, dtype=float) + offset
        if orientation is not None:
            orientation = np.asarray(quaternion_multiply(orientation,
                                                         quaternion_conjugate(turn)))
        return position, orientation

    def next_check_step(self, count):
        """Return the step of check number `count`, or -1 after the last check."""
        return self.check_step_list[count] if count < self.num_checks else -1

    def should_stop(self, check, position, orientation):
        """Return True if early termination stops the rollout at check `check`."""
        if not self._termination_list[check]:
            return False
        table = self._position
        start, end = table['start_list'][check], table['end_list'][check]
        if end > start:
            distance = position_distance(position, table['target'][start:end], self.distance,
                                         table['mask'][start:end])
            if np.any(distance > self.position_margin):
                return True
        table = self._orientation
        start, end = table['start_list'][check], table['end_list'][check]
        if end > start:
            angle = orientation_angle(orientation, table['target'][start:end])
            if np.any(angle > self.orientation_margin):
                return True
        return False

    def sample_errors(self, positions, orientations, num_recorded):
        """Return (objective index, error) arrays of the samples of the first checks."""
        parts = []
        for table, values in ((self._position, positions), (self._orientation, orientations)):
            count = int(np.searchsorted(table['check'], num_recorded, side='left'))
            measured = np.asarray(values)[table['check'][:count]]
            if table is self._position:
                errors = position_distance(measured, table['target'][:count], self.distance,
                                           table['mask'][:count])
            else:
                errors = orientation_angle(measured, table['target'][:count])
            parts.append((table['objective'][:count], errors))
        return (np.concatenate([parts[0][0], parts[1][0]]),
                np.concatenate([parts[0][1], parts[1][1]]))

    def objective_values(self, positions, orientations, num_recorded,
                         margins: Optional[np.ndarray] = None):
        """
        Return h_o of one world per objective: eq. (5)'s inner mean, or eq. (6) when cut.

        positions (checks x 3) and orientations (checks x 4) hold the object pose read at
        each check; only the first `num_recorded` rows count. A rollout with fewer rows than
        checks was cut at the last recorded check (t = 0 if none): goals after it are charged
        `margins` (default: the task's d_s / theta_s per objective) as eq. (6) says. With an
        orientation symmetry, orientations must be a Trace's (the nearest symmetric turns).
        """
        objectives, errors = self.sample_errors(positions, orientations, num_recorded)
        sums = np.bincount(objectives, weights=errors, minlength=self.num_objectives)
        return self._charged(sums, num_recorded, margins)

    def margin_values(self):
        """
        Return h'_o of a whole rollout (to the horizon, if any) missing every goal by s_o.

        The horizon rule's yardstick: a design at or below it in every objective tracks the
        goals up to the horizon within the margins on average.
        """
        objectives, _ = self.sample_errors(np.zeros((self.num_checks, 3)),
                                           np.zeros((self.num_checks, 4)), self.num_checks)
        sums = np.bincount(objectives, weights=self.margins[objectives],
                           minlength=self.num_objectives)
        return self._charged(sums, self.num_checks)

    def _charged(self, sums, num_recorded, margins=None):
        """Return eq. (5)'s mean of the error sums, or eq. (6) for a rollout cut short."""
        if num_recorded >= self.all_checks:
            return sums / self.objective_sizes
        margins = self.margins if margins is None else np.asarray(margins, dtype=float)
        if margins is None:
            raise ValueError('a rollout cut before its last check needs margins s_o; the task '
                             'has no early_termination')
        stop_time = self.check_times[num_recorded - 1] if num_recorded > 0 else 0.0
        end, begin = self.objective_end_times, self.objective_start_times
        remaining = (end - stop_time) / (end - begin)  # a_o
        cut = sums / self.objective_sizes + remaining * margins
        return np.where(end <= stop_time + 1e-12, sums / self.objective_sizes, cut)

    def pose_errors(self, position, orientation, start=None):
        """
        Return (distance, angle) of a pose from the last goals (of the world of `start`).

        A kind of goal the task does not have (Task 6's "final position irrelevant") is 0.
        """
        transform = self.start_transform(start)
        if transform is not None:
            position, orientation = _to_nominal(transform, position, orientation)
        turns = self.world_symmetries(transform)
        if turns is not None:
            orientation = _nearest_turn(orientation, turns, self.last_orientation)
        angle = (float(orientation_angle(orientation, self.last_orientation))
                 if self.has_orientation_goals else 0.0)
        return (float(position_distance(position, self.last_position, self.distance,
                                        self.last_mask)), angle)

    def world_symmetries(self, transform):
        """
        Return the symmetric turns (order x 4) that act on mapped orientations, or None.

        A symmetric turn s of the object's own frame makes q and q * s the same pose; mapped
        to the nominal start that is q * turn and q * turn * (turn^-1 * s * turn).
        """
        if self.symmetries is None:
            return None
        if transform is None:
            return self.symmetries
        turn = np.asarray(transform[1], dtype=float)
        inverse = quaternion_conjugate(turn)
        return np.array([quaternion_multiply(quaternion_multiply(inverse, s), turn)
                         for s in self.symmetries])

    def check_orientation_target(self, check):
        """Return the orientation target of check `check` (the last goal's if it has none)."""
        table = self._orientation
        start, end = table['start_list'][check], table['end_list'][check]
        return table['target'][start] if end > start else self.last_orientation


class Trace:
    """The object poses of one rollout at the schedule's checks, preallocated."""

    __slots__ = ('schedule', 'positions', 'orientations', 'count', 'transform', 'turns')

    def __init__(self, schedule: GoalSchedule, transform=None):
        self.schedule = schedule
        self.positions = np.zeros((schedule.num_checks, 3))
        self.orientations = np.zeros((schedule.num_checks, 4))
        self.count = 0
        self.transform = transform  # GoalSchedule.start_transform of the world, or None
        self.turns = schedule.world_symmetries(transform)  # None without a symmetry

    def record(self, position, orientation):
        """Store the pose of the next check; return True if early termination stops here."""
        check = self.count
        if self.transform is not None:
            position, orientation = _to_nominal(self.transform, position, orientation)
        if self.turns is not None:
            orientation = _nearest_turn(orientation, self.turns,
                                        self.schedule.check_orientation_target(check))
        self.positions[check] = position
        self.orientations[check] = orientation
        self.count = check + 1
        return self.schedule.should_stop(check, position, orientation)

    def objective_values(self, margins=None):
        """Return this world's h_o (or h'_o) per objective."""
        return self.schedule.objective_values(self.positions, self.orientations, self.count,
                                              margins)


def _axes_mask(axes):
    """Return 1.0 for each of x, y, z a position goal measures, else 0.0."""
    return np.array([1.0 if axis in axes else 0.0 for axis in 'xyz'])


def _symmetry_turns(symmetry):
    """Return the unit quaternions of the object's symmetric turns (order x 4), or None."""
    if symmetry is None:
        return None
    return np.array([axis_angle_quaternion(symmetry.axis, 2.0 * math.pi * k / symmetry.order)
                     for k in range(symmetry.order)])


def _nearest_turn(orientation, turns, target):
    """Return the orientation * turn (of `turns`) at the smallest eq. (4) angle to target."""
    # a product per turn in Python floats: numpy's cost per call outweighs four components'
    # arithmetic, and the operations (so the bits) are those of the product over arrays
    candidates = np.array([quaternion_multiply(orientation, turn)
                           for turn in np.asarray(turns).tolist()])
    inner = candidates @ np.asarray(target, dtype=float)
    return candidates[int(np.argmax(np.abs(inner)))]


def _to_nominal(transform, position, orientation):
    offset, turn = transform
    return (np.asarray(position, dtype=float) - offset,
            quaternion_multiply(orientation, turn))


_SCHEDULES = {}


def goal_schedule(task: Task) -> GoalSchedule:
    """Return the GoalSchedule of a task (built once per distinct task and reused)."""
    key = (task.source_text, task.source, task.time_step, task.duration, task.goals,
           task.early_termination, task.object_spec, task.horizon)
    schedule = _SCHEDULES.get(key)
    if schedule is None:
        if len(_SCHEDULES) > 64:
            _SCHEDULES.clear()
        schedule = _SCHEDULES[key] = GoalSchedule(task)
    return schedule
