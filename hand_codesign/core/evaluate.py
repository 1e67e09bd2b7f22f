"""
evaluate(x, task): the objective vector of one candidate over the task's world states.

The candidate's genome decodes into a Design; the Simulator builds its hand once, checks the
start of every world for collisions (then every objective is COLLISION_PENALTY and nothing is
simulated, eq. 5) and runs one rollout per world. Each world gives h_o per objective (eq. 5's
inner mean, eq. 6 when early termination cut it, UNSTABLE_PENALTY when the simulation became
unstable); the objectives are their mean over the worlds plus the torque penalty of eq. (2).

evaluate is a pure function of (x, task, worlds): the process-wide Simulator is reset and
rebuilt for every candidate, so results are bit-identical in any process and in any order.
"""

from dataclasses import dataclass
from typing import Optional, Sequence, Tuple

from hand_codesign.core.genome import genome_spec
from hand_codesign.core.hand import hand_model
from hand_codesign.core.objectives import (COLLISION_PENALTY, combine_worlds, goal_schedule,
                                           task_torque_penalty, weighted_fitness)
from hand_codesign.core.policies import make_policy
from hand_codesign.core.sim import object_shape, Simulator
from hand_codesign.core.worlds import object_state, world_states
import numpy as np

# h_o of every objective of a world whose simulation became unstable (NaN or exploding):
# as bad as a collision, but only for that world, so the mean stays finite and ranks designs.
UNSTABLE_PENALTY = COLLISION_PENALTY


@dataclass(frozen=True)
class Evaluation:
    """The result of one candidate; see the contract in hand_codesign.core."""

    objectives: np.ndarray  # one per objective name: eq. (5) with the torque penalty
    objective_names: Tuple[str, ...]
    fitness: float  # weighted sum with task.objective_weights
    world_objectives: np.ndarray  # (worlds, objectives): h_o of each world
    collision: bool  # the design starts in collision: every objective is COLLISION_PENALTY
    unstable_worlds: int
    simulated_time: float  # s, summed over the worlds
    initial_errors: np.ndarray  # (worlds, 2): position, orientation error w.r.t. the last
    final_errors: np.ndarray  # goal at t = 0 and at the end of the rollout


_SIMULATOR = None
_SPEC_CACHE = [None, None]  # the last task and its GenomeSpec


def shared_simulator():
    """Return this process's Simulator (created on first use)."""
    global _SIMULATOR
    if _SIMULATOR is None or _SIMULATOR.client is None:
        _SIMULATOR = Simulator()
    return _SIMULATOR


def _genome_spec(task):
    if _SPEC_CACHE[0] is not task:
        _SPEC_CACHE[:] = [task, genome_spec(task)]
    return _SPEC_CACHE[1]


def evaluate(x, task, worlds: Optional[Sequence] = None) -> 'Evaluation':
    """Return the Evaluation of normalized genome x on `task` (default worlds: the task's)."""
    design = _genome_spec(task).decode(np.asarray(x, dtype=float))
    return evaluate_design(design, task, worlds)


def evaluate_design(design, task, worlds: Optional[Sequence] = None,
                    simulator: Optional[Simulator] = None, on_frame=None, frame_every=1,
                    on_world=None):
    """
    Return the Evaluation of a Design on `task`.

    `simulator` defaults to the process-wide one. For replay: `on_world(index, simulator)`
    is called before each world's rollout and `on_frame(step, simulator)` at its frames
    (see Simulator.rollout).
    """
    worlds = world_states(task) if worlds is None else list(worlds)
    simulator = shared_simulator() if simulator is None else simulator
    schedule = goal_schedule(task)
    model = hand_model(design.hand, task.hand)
    policy = make_policy(task.policy, design.controller, model.initial_angles,
                         task.time_step)
    peak = design.controller.values if task.policy.kind == 'torque' else ()
    penalty = task_torque_penalty(task, peak)
    simulator.build(task, model)
    states = [object_state(task, world) for world in worlds]
    objects = [(state, object_shape(simulator.client, state, task.object_spec.shape))
               for state in states]
    initial = np.array([schedule.pose_errors(s.position, s.orientation) for s in states])
    initial = initial.reshape(len(states), 2)
    num_objectives = schedule.num_objectives
    if simulator.start_collisions(objects):
        world_values = np.full((len(states), num_objectives), COLLISION_PENALTY)
        return _evaluation(task, combine_worlds(world_values, collision=True), world_values,
                           True, 0, 0.0, initial, initial.copy())
    world_values = np.empty((len(states), num_objectives))
    final = np.empty((len(states), 2))
    unstable_worlds, steps = 0, 0
    for index, (state, shape) in enumerate(objects):
        if on_world is not None:
            on_world(index, simulator)
        result = simulator.rollout(state, shape, policy, schedule, on_frame, frame_every)
        steps += result.steps
        if result.unstable:
            unstable_worlds += 1
            world_values[index] = UNSTABLE_PENALTY
        else:
            world_values[index] = result.trace.objective_values()
        final[index] = schedule.pose_errors(result.final_position, result.final_orientation)
    objectives = combine_worlds(world_values, penalty)
    return _evaluation(task, objectives, world_values, False, unstable_worlds,
                       steps * task.time_step, initial, final)


def _evaluation(task, objectives, world_values, collision, unstable_worlds, simulated_time,
                initial, final):
    return Evaluation(objectives=np.asarray(objectives, dtype=float),
                      objective_names=tuple(task.objective_names),
                      fitness=weighted_fitness(objectives, task.objective_weights),
                      world_objectives=world_values, collision=bool(collision),
                      unstable_worlds=int(unstable_worlds),
                      simulated_time=float(simulated_time), initial_errors=initial,
                      final_errors=final)
