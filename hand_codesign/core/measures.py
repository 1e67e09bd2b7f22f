"""
What a reproduced experiment measures of one design, on worlds it was never trained on.

A run optimizes on `core.worlds.world_states(task)`: draws from a numpy Generator seeded with
the run's seed. `unseen_world_states(task, count)` draws from another stream of the same seed
(`default_rng([seed, UNSEEN_STREAM])`, a different SeedSequence), uniform in the same ranges,
so the measuring worlds are disjoint from the training worlds (continuous draws; checked) and
the first k of a larger set are the k of a smaller one.

Per world, from the very rollout that `core.evaluate` runs (the same simulator, design and
policy; the measure only looks at the scene, it never changes it):

- the final errors with respect to the last goal: `position` (eq. 3's distance, m, over the
  goal's axes), `plane` (the distance in the plane of the table, x and y of the world: a
  scaled box rests higher, a height no hand can change), `x` and `y` (the distance along one
  world axis: a hand whose fingers all swing in the x-z plane pushes along x and leaves y
  where the world put it) and `orientation` (eq. 4's angle, rad);
- **resting on a limit while touching** (`limit_contacts`): at the end of the rollout (its
  last step, or the goal check where early termination stopped it) some finger has a joint
  within LIMIT_TOLERANCE of one of its limits (or past it: Bullet's limits are soft) and
  the same finger touches the object (a contact point between any segment of that finger and
  the object with a separation of at most CONTACT_DISTANCE). The rule is core.outcomes'
  (`resting_on_limit_touching`), which a quality-diversity search also measures in its own
  rollouts (the outcome descriptor limit_rest); here it is read at the last frame of a
  rollout, so an unstable world gives the state of its last stable frame.

Per design (`DesignMeasures`): the share of worlds within the tolerance, the median and 90th
percentile of the error, and **joint limits found**: the design rests on a limit while
touching in at least LIMITS_FOUND_SHARE of the worlds it did not start in collision with.
A world the design starts in collision with is not simulated: its final error is its initial
one and it never counts as touching.
"""

import dataclasses
import math
from typing import Optional

from hand_codesign.core.evaluate import _TaskContext, evaluate_design
# the rule of resting on a limit while touching is core.outcomes' (evaluate uses it too)
from hand_codesign.core.outcomes import resting_on_limit_touching
from hand_codesign.core.robustness import map_chunks, start_and_goal_poses
from hand_codesign.core.worlds import WorldState
import numpy as np

UNSEEN_STREAM = 11  # second entropy word of the unseen worlds' SeedSequence
LIMITS_FOUND_SHARE = 0.5  # share of the worlds in which the design must rest on a limit
ERROR_KINDS = ('position', 'plane', 'x', 'y', 'orientation')
AXES = ('x', 'y')  # the error kinds along one world axis
CHUNK = 50


@dataclasses.dataclass(frozen=True)
class Tolerance:
    """Success on one world: its `kind` error (ERROR_KINDS) below `limit` (m or rad)."""

    kind: str
    limit: float

    def describe(self):
        """Return e.g. 'plane error < 5 mm'."""
        if self.kind == 'orientation':
            return f'orientation error < {self.limit:g} rad'
        if self.kind in AXES:
            return f'error along {self.kind} < {self.limit * 1000:g} mm'
        return f'{self.kind} error < {self.limit * 1000:g} mm'


def unseen_world_states(task, count):
    """Return `count` worlds of the task's ranges from a stream disjoint from its training."""
    generator = np.random.default_rng([int(task.seed), UNSEEN_STREAM])
    uniform = generator.random((int(count), 7))
    bounds = [bounds for _, bounds in task.randomization.quantities()]
    lower = np.array([bound.lower for bound in bounds])
    width = np.array([bound.width for bound in bounds])
    return [WorldState.from_values(row) for row in lower + uniform * width]


@dataclasses.dataclass(frozen=True)
class WorldMeasures:
    """Per world: the three final errors, start collisions, resting on a limit while touching."""

    errors: dict  # kind -> (worlds,) final error
    initial_errors: dict  # kind -> (worlds,) error at the start
    collisions: np.ndarray  # (worlds,) bool
    limit_contacts: np.ndarray  # (worlds,) bool
    final_positions: Optional[np.ndarray] = None  # (worlds, 3) m, world frame; not cached


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
    joint_limits_found: bool
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
    """Return the WorldMeasures of normalized genome x on `worlds` (a pool if processes > 1)."""
    worlds = tuple(worlds)
    if not worlds:
        raise ValueError('measure_worlds needs at least one world')
    parts = map_chunks(_measure_chunk, x, task, worlds, CHUNK, processes)
    initial, final, final_poses, collisions, contacts = (np.concatenate(column)
                                                         for column in zip(*parts))
    starts, goals = start_and_goal_poses(task, worlds)
    errors = dict(_offsets(final_poses, goals), position=final[:, 0],
                  orientation=final[:, 1])
    initial_errors = dict(_offsets(starts, goals), position=initial[:, 0],
                          orientation=initial[:, 1])
    return WorldMeasures(errors, initial_errors, collisions, contacts, final_poses[:, :3])


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
    return DesignMeasures(
        worlds=int(len(errors)), tolerance=tolerance,
        within=float(np.mean(errors < tolerance.limit)),
        median=float(np.median(errors)), p90=float(np.percentile(errors, 90)),
        initial_median=float(np.median(measures.initial_errors[tolerance.kind])),
        limit_contact_share=share,
        joint_limits_found=bool(simulated.any() and share >= LIMITS_FOUND_SHARE),
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


class LimitContactWatch:
    """An on_world / on_frame pair for evaluate_design: resting on a limit while touching."""

    def __init__(self, count):
        self.flags = np.zeros(count, dtype=bool)
        self.world = 0

    def on_world(self, index, simulator):
        self.world = index
        self.flags[index] = False

    def on_frame(self, step, simulator):
        # every frame overwrites the flag: the last one is the rollout's end
        self.flags[self.world] = resting_on_limit_touching(simulator)


def _measure_chunk(job):
    x, task, worlds = job
    design = _TaskContext.of(task).genome_spec().decode(x)
    watch = LimitContactWatch(len(worlds))
    evaluation = evaluate_design(design, task, list(worlds), on_frame=watch.on_frame,
                                 frame_every=frame_interval(_TaskContext.of(task).schedule),
                                 on_world=watch.on_world)
    if evaluation.collision and len(worlds) > 1:
        # a collision in one world marks the whole chunk: find the worlds that collide
        parts = [_measure_chunk((x, task, (world,))) for world in worlds]
        return tuple(np.concatenate(column) for column in zip(*parts))
    return (evaluation.initial_errors, evaluation.final_errors, evaluation.final_poses,
            np.full(len(worlds), evaluation.collision), watch.flags & ~evaluation.collision)


__all__ = ['DesignMeasures', 'measure_design', 'measure_worlds', 'summarize', 'Tolerance',
           'unseen_world_states', 'WorldMeasures']
