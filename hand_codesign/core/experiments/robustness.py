"""
Robustness of a final design over many world states: the data of the paper's Fig. 3.

The paper compares designs on the same 15,625 domain-randomization samples, five values on each
of six randomized quantities (`grid_world_states(task, 5)`), reporting for every sample the
object's position and orientation error with respect to the last goal at the start and at the
end of the rollout::

    report = evaluate_robustness(x, task, processes=2)    # default: the 5-value grid
    report.final_errors[:, 0]                             # position errors, one per world
    report.success_rate(0.005, 0.05)

Worlds are evaluated in chunks with core.evaluate, optionally by a pool of processes; results
are the same in any process and with any chunking. A chunk in which the design starts in
collision is evaluated again world by world, so that `collisions` names the very worlds (a
colliding world is not simulated: its final errors are its initial errors).

The report also keeps, per world and in the world frame, the object's start pose, the last goal
(moved with the start when the task's goals are relative to it) and the object's final pose, so
that `worlds.csv` lets anyone recompute the errors (eq. 3 and 4) without this code.
"""

import concurrent.futures
import csv
import dataclasses
import multiprocessing
from typing import Optional, Sequence

from hand_codesign.core.evaluate import evaluate
from hand_codesign.core.sim.objectives import goal_schedule
from hand_codesign.core.sim.worlds import grid_world_states, object_state, QUANTITIES
import numpy as np

DEFAULT_CHUNK = 125
POSE_AXES = ('position_x', 'position_y', 'position_z',
             'orientation_x', 'orientation_y', 'orientation_z', 'orientation_w')


@dataclasses.dataclass(frozen=True)
class RobustnessReport:
    """Per world: its values, start, goal and final poses, the errors, whether it collided."""

    worlds: tuple  # WorldState per sample
    initial_errors: np.ndarray  # (worlds, 2): position (m), orientation (rad) at t = 0
    final_errors: np.ndarray  # (worlds, 2): the same at the end of the rollout
    collisions: np.ndarray  # (worlds,) bool: the design starts in collision in that world
    # (worlds, 7) each, world frame: position (m), then quaternion x, y, z, w
    start_poses: np.ndarray  # the object at t = 0
    goal_poses: np.ndarray  # the last goals the errors are measured from
    final_poses: np.ndarray  # the object at the end of the rollout (the start if collided)

    @property
    def size(self):
        """Return the number of worlds."""
        return len(self.worlds)

    def success_rate(self, position_threshold, orientation_threshold):
        """Return the fraction of worlds ending within both thresholds."""
        within = ((self.final_errors[:, 0] <= position_threshold) &
                  (self.final_errors[:, 1] <= orientation_threshold))
        return float(np.mean(within))

    def summary(self):
        """Return {'initial'|'final': {'position'|'orientation': {statistic: value}}}."""
        statistics = {}
        for when, errors in (('initial', self.initial_errors), ('final', self.final_errors)):
            statistics[when] = {
                kind: {'mean': float(np.mean(errors[:, column])),
                       'median': float(np.median(errors[:, column])),
                       'p90': float(np.percentile(errors[:, column], 90)),
                       'max': float(np.max(errors[:, column]))}
                for column, kind in enumerate(('position', 'orientation'))}
        statistics['collision_rate'] = float(np.mean(self.collisions))
        return statistics

    def write_csv(self, path):
        """
        Write one row per world: its values, the four errors, the collision flag and poses.

        The poses (start_*, goal_*, final_*, each position_x..z in m and orientation_x..w)
        come last, so that the older columns keep their places.
        """
        pose_columns = [f'{when}_{axis}' for when in ('start', 'goal', 'final')
                        for axis in POSE_AXES]
        with open(path, 'w', newline='', encoding='utf-8') as stream:
            writer = csv.writer(stream)
            writer.writerow(list(QUANTITIES) + [
                'initial_position_error', 'initial_orientation_error',
                'final_position_error', 'final_orientation_error', 'collision'] + pose_columns)
            for index, world in enumerate(self.worlds):
                writer.writerow([*world_values(world), *self.initial_errors[index],
                                 *self.final_errors[index], int(self.collisions[index]),
                                 *self.start_poses[index], *self.goal_poses[index],
                                 *self.final_poses[index]])


def world_values(world):
    """Return a world's seven values in QUANTITIES order."""
    return (*world.position_delta, world.orientation_delta, world.friction_delta, world.scale,
            world.mass_factor)


def evaluate_robustness(x, task, worlds: Optional[Sequence] = None, values_per_quantity=5,
                        processes=1, chunk_size=DEFAULT_CHUNK):
    """
    Evaluate normalized genome x of `task` on many worlds; return a RobustnessReport.

    worlds defaults to grid_world_states(task, values_per_quantity). With processes > 1 the
    chunks go to a pool of that many fresh (spawned) processes.
    """
    worlds = tuple(grid_world_states(task, values_per_quantity) if worlds is None else worlds)
    if not worlds:
        raise ValueError('evaluate_robustness needs at least one world state')
    if chunk_size < 1 or processes < 1:
        raise ValueError(f'chunk_size and processes must be >= 1, got {chunk_size}, '
                         f'{processes}')
    parts = map_chunks(_evaluate_chunk, x, task, worlds, chunk_size, processes)
    initial, final, collisions, final_poses = (np.concatenate(column)
                                               for column in zip(*parts))
    starts, goals = start_and_goal_poses(task, worlds)
    return RobustnessReport(worlds, initial, final, collisions, starts, goals, final_poses)


def map_chunks(function, x, task, worlds, chunk_size, processes):
    """
    Return [function((x, task, chunk)) for each chunk of `worlds`], in world order.

    With processes > 1 the chunks run in a pool of spawned processes (each builds its own
    PyBullet client); the results are the same as in one process.
    """
    x = np.array(x, dtype=float)
    jobs = [(x, task, worlds[start:start + chunk_size])
            for start in range(0, len(worlds), chunk_size)]
    if processes <= 1 or len(jobs) == 1:
        return [function(job) for job in jobs]
    # A process pool executor fails (BrokenProcessPool) where a multiprocessing.Pool would
    # wait forever for workers that cannot start.
    spawn = multiprocessing.get_context('spawn')
    with concurrent.futures.ProcessPoolExecutor(min(processes, len(jobs)),
                                                mp_context=spawn) as pool:
        return list(pool.map(function, jobs))


def start_and_goal_poses(task, worlds):
    """Return (start poses, last goal poses) of the worlds, (worlds, 7) each, world frame."""
    schedule = goal_schedule(task)
    starts, goals = [], []
    for world in worlds:
        state = object_state(task, world)
        position, orientation = schedule.world_goal(schedule.last_position,
                                                    schedule.last_orientation, state)
        starts.append((*state.position, *state.orientation))
        goals.append((*position, *orientation))
    return (np.array(starts, dtype=float).reshape(-1, 7),
            np.array(goals, dtype=float).reshape(-1, 7))


def _evaluate_chunk(job):
    x, task, worlds = job
    evaluation = evaluate(x, task, worlds=list(worlds))
    if not evaluation.collision or len(worlds) == 1:
        return (evaluation.initial_errors, evaluation.final_errors,
                np.full(len(worlds), evaluation.collision), evaluation.final_poses)
    # A collision in one world marks the whole chunk; find the worlds that collide.
    parts = [_evaluate_chunk((x, task, (world,))) for world in worlds]
    return tuple(np.concatenate(column) for column in zip(*parts))


__all__ = ['evaluate_robustness', 'map_chunks', 'RobustnessReport', 'start_and_goal_poses',
           'world_values']
