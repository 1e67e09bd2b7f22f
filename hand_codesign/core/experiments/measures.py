"""
What a reproduced experiment measures of one design, on worlds it was never trained on.

A run optimizes on `core.sim.worlds.world_states(task)`: draws from a numpy Generator seeded with
the run's seed. `unseen_world_states(task, count)` draws from another stream of the same seed
(`default_rng([seed, UNSEEN_STREAM])`, a different SeedSequence), uniform in the same ranges,
so the measuring worlds are disjoint from the training worlds (continuous draws; checked) and
the first k of a larger set are the k of a smaller one.

Every unseen world runs the whole motion (`full_motion`): the task's early termination and a
candidate's horizon are what the search uses to save time, not part of what the design does,
so a measure never reads a rollout where a training rule stopped it.

Per world, from the very rollout that `core.evaluate` runs (the same simulator, design and
policy; the measure only looks at the scene, it never changes it):

- the final errors with respect to the last goal: `position` (eq. 3's distance, m, over the
  goal's axes), `plane` (the distance in the plane of the table, x and y of the world: a
  scaled box rests higher, a height no hand can change), `x` and `y` (the distance along one
  world axis), `orientation` (eq. 4's angle, rad) and `pose`, the plane and orientation errors
  together in units of their tolerances (max(plane / 5 mm, orientation / 0.1 rad): below 1
  when both are within, Task 4's "turn the box, keep its position");
- **resting on a limit while touching** (`limit_contacts`): at the end of the rollout some
  finger has a joint within LIMIT_TOLERANCE of one of its limits (or past it: Bullet's limits
  are soft) and the same finger touches the object (a contact point between any segment of
  that finger and the object with a separation of at most CONTACT_DISTANCE). The rule is
  core.outcomes' (`resting_on_limit_touching`), which a quality-diversity search also
  measures in its own rollouts (the outcome descriptor limit_rest);
- **resting on a reached limit while touching** (`limit_reached`): the same, with a joint on
  a limit that its initial angle was not already on (`resting_on_reached_limit_touching`).
  Both are read at the last frame of a rollout, so an unstable world gives the state of its
  last stable frame;
- **what the hand did** (`touched`, `touching`): whether a finger (not the palm) touched the
  object at any frame of the rollout (frames every TOUCH_EVERY steps and at every goal check)
  and whether one touches it at the end; with the limit flags they say whether a design never
  reaches the object, lets it go, or holds it on a joint limit or off its limits.

Per design (`DesignMeasures`): the share of worlds within the tolerance, the median and 90th
percentile of the error, and **joint limits found**, the paper's mechanism: in a world, the
object ends within the tolerance while the design rests on a limit it reached, touching the
object (a *limit success*); the design found its joint limits when its limit successes are at
least LIMITS_FOUND_SHARE of its successes and at least LIMITS_FOUND_MIN_SHARE of all its
worlds. So a design that leans on a limit in the worlds it fails, or that starts a joint on
its limit and leaves it there, has not found them. The earlier, looser rule (resting on a
limit while touching in at least half of the worlds, whatever the outcome) is kept as
`limit_contact_share` for comparison. A world the design starts in collision with is not
simulated: its final error is its initial one and it never counts as touching.
"""

import dataclasses
import math
from typing import Optional

from hand_codesign.core.evaluate import _TaskContext, evaluate_design
# the rule of resting on a limit while touching is core.outcomes' (evaluate uses it too)
from hand_codesign.core.experiments.robustness import map_chunks, start_and_goal_poses
from hand_codesign.core.outcomes import (limit_rests, on_its_limit, reached_its_limit,
                                         touching_links)
from hand_codesign.core.sim.worlds import with_contact, WorldState
import numpy as np

UNSEEN_STREAM = 11  # second entropy word of the unseen worlds' SeedSequence
LIMITS_FOUND_SHARE = 0.5  # share of its successes that must be limit successes
LIMITS_FOUND_MIN_SHARE = 0.25  # share of all its worlds that must be limit successes
# the tolerances a pose error is measured in: Task 4's box turned and kept in place
POSE_PLANE_LIMIT = 0.005  # m
POSE_ORIENTATION_LIMIT = 0.1  # rad
ERROR_KINDS = ('position', 'plane', 'x', 'y', 'orientation', 'pose')
AXES = ('x', 'y')  # the error kinds along one world axis
CHUNK = 50
TOUCH_EVERY = 10  # physics steps between the frames that look for a touch (0.05 s at 5 ms)


@dataclasses.dataclass(frozen=True)
class Tolerance:
    """Success on one world: its `kind` error (ERROR_KINDS) below `limit` (m or rad)."""

    kind: str
    limit: float

    def describe(self):
        """Return e.g. 'plane error < 5 mm'."""
        if self.kind == 'pose':
            return (f'plane error < {POSE_PLANE_LIMIT * 1000:g} mm and orientation error < '
                    f'{POSE_ORIENTATION_LIMIT:g} rad')
        if self.kind == 'orientation':
            return f'orientation error < {self.limit:g} rad'
        if self.kind in AXES:
            return f'error along {self.kind} < {self.limit * 1000:g} mm'
        return f'{self.kind} error < {self.limit * 1000:g} mm'


# The tolerances the experiments (hand_codesign.campaign) and `analyze --unseen` measure by
PLANE_5MM = Tolerance('plane', 0.005)
POSITION_5MM = Tolerance('position', 0.005)
ALONG_X_5MM = Tolerance('x', 0.005)
ALONG_Y_5MM = Tolerance('y', 0.005)
ORIENTATION_01 = Tolerance('orientation', 0.1)
# Task 4: turn the box and keep its position: within 5 mm in the plane and 0.1 rad at once
POSE = Tolerance('pose', 1.0)


def unseen_world_states(task, count):
    """Return `count` worlds of the task's ranges from a stream disjoint from its training."""
    generator = np.random.default_rng([int(task.seed), UNSEEN_STREAM])
    uniform = generator.random((int(count), 7))
    bounds = [bounds for _, bounds in task.randomization.quantities()]
    lower = np.array([bound.lower for bound in bounds])
    width = np.array([bound.width for bound in bounds])
    worlds = [WorldState.from_values(row) for row in lower + uniform * width]
    return with_contact(task, worlds, [int(task.seed), UNSEEN_STREAM])


@dataclasses.dataclass(frozen=True)
class WorldMeasures:
    """Per world: the final errors, start collisions, resting on a limit while touching."""

    errors: dict  # kind -> (worlds,) final error
    initial_errors: dict  # kind -> (worlds,) error at the start
    collisions: np.ndarray  # (worlds,) bool
    limit_contacts: np.ndarray  # (worlds,) bool: on a limit, touching (the looser rule)
    limit_reached: np.ndarray  # (worlds,) bool: on a limit it reached, touching
    final_positions: Optional[np.ndarray] = None  # (worlds, 3) m, world frame; not cached
    touched: Optional[np.ndarray] = None  # (worlds,) bool: a finger touched it at some frame
    touching: Optional[np.ndarray] = None  # (worlds,) bool: a finger touches it at the end
    final_orientations: Optional[np.ndarray] = None  # (worlds, 4) (x, y, z, w); not cached


@dataclasses.dataclass(frozen=True)
class DesignMeasures:
    """One design's measures on unseen worlds under one tolerance."""

    worlds: int
    tolerance: Tolerance
    within: float  # share of worlds within the tolerance
    median: float  # of the tolerance's error (m or rad)
    p90: float
    initial_median: float  # the same error at the start, for comparison
    limit_contact_share: float  # share of non-colliding worlds resting on a limit, touching
    # limit successes (within the tolerance, on a reached limit, touching): their share of
    # all the worlds and of the worlds within the tolerance
    limit_success_share: float
    limit_share_of_successes: float
    joint_limits_found: bool  # limit successes >= half the successes, >= a quarter of all
    collision_share: float

    def as_dict(self):
        """Return the measures as plain JSON values."""
        values = dataclasses.asdict(self)
        values['tolerance'] = dataclasses.asdict(self.tolerance)
        return values

    @classmethod
    def from_dict(cls, values):
        """Return the DesignMeasures of as_dict()'s output."""
        return cls(**dict(values, tolerance=Tolerance(**values['tolerance'])))


def measure_worlds(x, task, worlds, processes=1):
    """
    Return the WorldMeasures of a design on given worlds, each rollout run to its end.

    x is the design's normalized genome, shape (genes,), values in [0, 1]; task the Task it
    was found on, whose early termination and horizon are dropped (full_motion); worlds the
    WorldStates to measure on; processes the worker processes (1: this one; the result does
    not depend on it). The WorldMeasures hold per world the final and initial errors of
    ERROR_KINDS (m or rad; the pose error in units of its tolerances), start collisions and
    resting on a limit while touching. Raises ValueError without worlds.
    """
    worlds = tuple(worlds)
    if not worlds:
        raise ValueError('measure_worlds needs at least one world')
    task = full_motion(task)
    parts = map_chunks(_measure_chunk, x, task, worlds, CHUNK, processes)
    initial, final, final_poses, collisions, contacts, reached, touched, touching = (
        np.concatenate(column) for column in zip(*parts))
    starts, goals = start_and_goal_poses(task, worlds)
    errors = with_pose_error(dict(_offsets(final_poses, goals), position=final[:, 0],
                                  orientation=final[:, 1]))
    initial_errors = with_pose_error(dict(_offsets(starts, goals), position=initial[:, 0],
                                          orientation=initial[:, 1]))
    return WorldMeasures(errors, initial_errors, collisions, contacts, reached,
                         final_poses[:, :3], touched, touching, final_poses[:, 3:])


def full_motion(task):
    """Return the task without early termination or a horizon: rollouts run to the last goal."""
    if task.early_termination is None and task.horizon is None:
        return task
    return task.replace(early_termination=None, horizon=None)


def with_pose_error(errors):
    """Return errors (kind -> per-world array) with 'pose' added from 'plane' and 'orientation'."""
    pose = np.maximum(np.asarray(errors['plane']) / POSE_PLANE_LIMIT,
                      np.asarray(errors['orientation']) / POSE_ORIENTATION_LIMIT)
    return dict(errors, pose=pose)


def _offsets(poses, goals):
    """Return {'plane', 'x', 'y'}: the distances of the poses' positions from the goals'."""
    offsets = np.asarray(poses)[:, :2] - np.asarray(goals)[:, :2]
    return {'plane': np.linalg.norm(offsets, axis=1), 'x': np.abs(offsets[:, 0]),
            'y': np.abs(offsets[:, 1])}


def summarize(measures: WorldMeasures, tolerance: Tolerance):
    """Return the DesignMeasures of per-world measures under a tolerance."""
    if tolerance.kind not in ERROR_KINDS:
        raise ValueError(f'tolerance kind must be one of {ERROR_KINDS}, got {tolerance.kind!r}')
    errors = measures.errors[tolerance.kind]
    simulated = ~measures.collisions
    share = (float(np.mean(measures.limit_contacts[simulated])) if simulated.any() else 0.0)
    within = errors < tolerance.limit
    limit_successes = within & measures.limit_reached & simulated
    of_successes = float(limit_successes.sum() / within.sum()) if within.any() else 0.0
    of_all = float(np.mean(limit_successes))
    return DesignMeasures(
        worlds=int(len(errors)), tolerance=tolerance, within=float(np.mean(within)),
        median=float(np.median(errors)), p90=float(np.percentile(errors, 90)),
        initial_median=float(np.median(measures.initial_errors[tolerance.kind])),
        limit_contact_share=share, limit_success_share=of_all,
        limit_share_of_successes=of_successes,
        joint_limits_found=bool(of_successes >= LIMITS_FOUND_SHARE
                                and of_all >= LIMITS_FOUND_MIN_SHARE),
        collision_share=float(np.mean(measures.collisions)))


def shares_in_bands(values, within, edges):
    """
    Return [(low, high, worlds, share within)] of the worlds in each band [low, high).

    values: one value of a world quantity per world; within: whether each world ended within
    a tolerance; edges: increasing band edges. The last band includes its upper edge, so
    edges spanning a quantity's range take every world. A band without worlds has share None.
    """
    values, within = np.asarray(values), np.asarray(within, dtype=bool)
    bands = []
    for index, (low, high) in enumerate(zip(edges, edges[1:])):
        last = index == len(edges) - 2
        inside = (values >= low) & ((values <= high) if last else (values < high))
        share = float(np.mean(within[inside])) if inside.any() else None
        bands.append((float(low), float(high), int(inside.sum()), share))
    return bands


def measure_design(x, task, tolerance, count, processes=1):
    """Return the DesignMeasures of genome x on `count` unseen worlds of the task."""
    return summarize(measure_worlds(x, task, unseen_world_states(task, count), processes),
                     tolerance)


def frame_interval(schedule):
    """Return steps between frames so that every goal check (and the last step) has one."""
    if not schedule.num_checks:
        return schedule.num_steps
    return math.gcd(*schedule.check_step_list)


def watch_interval(schedule):
    """Return steps between the measure's frames: every TOUCH_EVERY steps and every check."""
    return math.gcd(frame_interval(schedule), TOUCH_EVERY)


class LimitContactWatch:
    """An on_world / on_frame pair for evaluate_design: resting on a limit while touching."""

    def __init__(self, count):
        self.flags = np.zeros(count, dtype=bool)  # on a limit, touching
        self.reached = np.zeros(count, dtype=bool)  # on a limit it reached, touching
        self.touched = np.zeros(count, dtype=bool)  # a finger touched it at some frame
        self.touching = np.zeros(count, dtype=bool)  # a finger touches it (the last frame)
        self.world = 0

    def on_world(self, index, simulator):
        self.world = index
        self.flags[index] = self.reached[index] = False
        self.touched[index] = self.touching[index] = False

    def on_frame(self, step, simulator):
        # every frame overwrites the flags: the last one is the rollout's end
        self.flags[self.world], self.reached[self.world] = limit_rests(
            simulator, (on_its_limit, reached_its_limit))
        # a finger, not the palm: an object lying on the palm is not held by the fingers
        self.touching[self.world] = any(link >= 0 for link in touching_links(simulator))
        self.touched[self.world] |= self.touching[self.world]


def _measure_chunk(job):
    x, task, worlds = job
    design = _TaskContext.of(task).genome_spec().decode(x)
    watch = LimitContactWatch(len(worlds))
    evaluation = evaluate_design(design, task, list(worlds), on_frame=watch.on_frame,
                                 frame_every=watch_interval(_TaskContext.of(task).schedule),
                                 on_world=watch.on_world)
    if evaluation.collision and len(worlds) > 1:
        # a collision in one world marks the whole chunk: find the worlds that collide
        parts = [_measure_chunk((x, task, (world,))) for world in worlds]
        return tuple(np.concatenate(column) for column in zip(*parts))
    simulated = not evaluation.collision   # a bool: ~ of a Python bool is -1, an int mask
    return (evaluation.initial_errors, evaluation.final_errors, evaluation.final_poses,
            np.full(len(worlds), evaluation.collision), watch.flags & simulated,
            watch.reached & simulated, watch.touched & simulated, watch.touching & simulated)


__all__ = ['DesignMeasures', 'full_motion', 'measure_design', 'measure_worlds', 'summarize',
           'Tolerance', 'unseen_world_states', 'with_pose_error', 'WorldMeasures']
