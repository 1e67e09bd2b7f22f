"""
evaluate(x, task): the objective vector of one candidate over the task's world states.

The candidate's genome decodes into a Design; the Simulator builds its hand once, checks the
start of every world for collisions (then every objective is COLLISION_PENALTY and nothing is
simulated, eq. 5) and runs one rollout per world. Each world gives h_o per objective (eq. 5's
inner mean, eq. 6 when early termination cut it, UNSTABLE_PENALTY when the simulation became
unstable); the objectives are their mean over the worlds plus the torque penalty of eq. (2),
or with `worlds: {aggregate: worst, fraction: f}` the mean over each objective's worst f of
the worlds (CVaR, core.sim.objectives.worst_mean) plus that penalty.

An unstable world counts UNSTABLE_PENALTY in its objectives. Under the mean it weighs 1 / n;
under the worst fraction it is always among the worst worlds and weighs 1 / (f n), so f n <= 1
scores a design with one unstable world like one that starts in collision (COLLISION_PENALTY,
or that plus the torque penalty): both rank behind every design that stays stable.

evaluate is a pure function of (x, task, worlds): the process-wide Simulator is reset and
rebuilt for every candidate, so results are bit-identical in any process and in any order.
A candidate's sub-problem (Candidate.horizon) is part of its task: task.replace(horizon=...).

When the task's quality-diversity archive names outcome descriptors (core.outcomes), each
world's scene is also read once at the end of its rollout and the Evaluation carries their
means over the worlds (`outcome_names`, `outcomes`); a design that starts in collision has
0 for each. Other tasks read nothing more.

A task in several physics engines (`physics: {engines: [pybullet, mujoco]}`) evaluates each
candidate on the same worlds in every engine and scores it by `physics.engine_aggregate`
(across_engines): the mean of the engines' objectives, or per objective the worse engine's.
Its per-world arrays stack the engines' rows, engine by engine.
"""

from dataclasses import dataclass, field
from typing import Any, Callable, Dict, Optional, Sequence, Tuple

from hand_codesign.core.design import Design
from hand_codesign.core.outcomes import OutcomeWatch, task_outcomes
from hand_codesign.core.sim.hand import hand_model
from hand_codesign.core.sim.objectives import (COLLISION_PENALTY, combine_worlds,
                                               design_torque_penalty, goal_schedule,
                                               weighted_fitness)
from hand_codesign.core.sim.policies import make_policy
from hand_codesign.core.sim.pybullet_sim import Simulator
from hand_codesign.core.sim.worlds import object_state, world_states, WorldState
from hand_codesign.core.task.genome import genome_spec
from hand_codesign.core.task.spec import Task
import numpy as np
from numpy.typing import ArrayLike

# called before each world's rollout: (index of the world, the simulator), or at its frames
OnWorld = Callable[[int, Any], None]

# h_o of every objective of a world whose simulation became unstable (NaN or exploding):
# as bad as a collision, but only for that world, so the mean stays finite and ranks designs.
UNSTABLE_PENALTY = COLLISION_PENALTY


@dataclass(frozen=True)
class Evaluation:
    """The result of one candidate; see the contract in hand_codesign.core."""

    objectives: np.ndarray  # one per objective name: eq. (5) with the torque penalty
    objective_names: Tuple[str, ...]
    fitness: float  # weighted sum with task.objective_weights
    # (worlds, objectives): h_o of each world; in several engines (engines * worlds, ...), the
    # engines' rows stacked in physics.engines' order, as are the errors and poses below
    world_objectives: np.ndarray
    collision: bool  # the design starts in collision: every objective is COLLISION_PENALTY
    unstable_worlds: int
    simulated_time: float  # s, summed over the worlds
    initial_errors: np.ndarray  # (worlds, 2): position, orientation error w.r.t. the last
    final_errors: np.ndarray  # goal at t = 0 and at the end of the rollout
    # (worlds, 7): the object's pose at the end of each rollout, world frame: position (m),
    # then quaternion x, y, z, w; the start pose where nothing was simulated (a collision),
    # the last finite pose of an unstable world. final_errors are measured from it.
    final_poses: np.ndarray
    # the outcome descriptors the task's archive names (core.outcomes) and their shares of
    # the worlds; empty for every other task
    outcome_names: Tuple[str, ...] = ()
    outcomes: np.ndarray = field(default_factory=lambda: np.zeros(0))


_SIMULATORS: Dict[str, Any] = {}  # engine name -> this process's simulator of that engine


def shared_simulator(engine='pybullet'):
    """Return this process's simulator of `engine` (task.physics.engine), made on first use."""
    simulator = _SIMULATORS.get(engine)
    if simulator is None or simulator.client is None:
        simulator = _SIMULATORS[engine] = new_simulator(engine)
    return simulator


def new_simulator(engine):
    """Return a new simulator of `engine`: 'pybullet' (core.sim.pybullet_sim) or 'mujoco'."""
    if engine == 'mujoco':
        # imported on first use: loading MuJoCo costs a process about 0.2 s
        from hand_codesign.core.sim.mujoco_sim import MujocoSimulator
        return MujocoSimulator()
    return Simulator()


class _TaskContext:
    """What every candidate of one task shares: genome, schedule, worlds and their objects."""

    current = None

    def __init__(self, task):
        self.task = task
        self.spec = None
        self.schedule = goal_schedule(task)
        self.outcome_names = task_outcomes(task)  # () unless its archive names some
        self.default_worlds = None
        self.worlds = {}  # tuple of WorldStates -> (object states, initial errors)

    @classmethod
    def of(cls, task):
        if cls.current is None or cls.current.task is not task:
            cls.current = cls(task)
        return cls.current

    def genome_spec(self):
        if self.spec is None:
            self.spec = genome_spec(self.task)
        return self.spec

    def objects(self, worlds):
        """Return (object states, initial errors) of a list of worlds (None: the task's)."""
        if worlds is None:
            if self.default_worlds is None:
                self.default_worlds = tuple(world_states(self.task))
            worlds = self.default_worlds
        key = tuple(worlds)
        entry = self.worlds.get(key)
        if entry is None:
            states = [object_state(self.task, world) for world in key]
            initial = np.array([self.schedule.pose_errors(state.position, state.orientation,
                                                          state)
                                for state in states]).reshape(len(states), 2)
            if len(self.worlds) > 8:
                self.worlds.clear()
            entry = self.worlds[key] = (states, initial)
        return entry


def evaluate(x: ArrayLike, task: Task, worlds: Optional[Sequence[WorldState]] = None,
             on_world: Optional[OnWorld] = None,
             share: Optional[Tuple[int, int]] = None) -> Evaluation:
    """
    Return the Evaluation of normalized genome x on `task` (default worlds: the task's).

    Deterministic: the same x, task, worlds and share give the same bits in any process.

    Args:
        x: the normalized genome, array-like of shape (genome_spec(task).size,), values
            folded into [0, 1] (outside values are mirrored back, never rejected).
        task: a core.task.Task, whose physics.engine chooses the simulator.
        worlds: WorldStates (core.sim.worlds) to evaluate on; None: world_states(task), the
            task's num_world_states training worlds.
        on_world: if given, `on_world(index, simulator)` is called before each world's
            rollout: a caller that must stay responsive (an evaluator's heartbeats) does its
            chores there.
        share: (first, end), a racing round's share of those worlds (core.search.racing):
            only worlds first..end-1 are simulated and scored, while the starts of all of
            them are checked for collisions (a design that starts in collision in any of
            them scores COLLISION_PENALTY in every round); None: all of them.

    Returns:
        The Evaluation: `objectives` (shape (objectives,), in task.objective_names' order:
        position errors in m, orientation errors in rad, eq. 5 over the worlds with the
        torque penalty), `fitness` (their sum weighted by task.objective_weights),
        `world_objectives` (shape (worlds, objectives), the share's worlds),
        `initial_errors` and `final_errors` (shape (worlds, 2): m, rad), `final_poses`
        (shape (worlds, 7): m, then a quaternion x, y, z, w), the simulated time (s), the
        count of unstable worlds and whether the design starts in collision (every
        objective then COLLISION_PENALTY).

    Raises:
        ValueError: for a genome of the wrong size.
    """
    design = _TaskContext.of(task).genome_spec().decode(np.asarray(x, dtype=float))
    return evaluate_design(design, task, worlds, on_world=on_world, share=share)


def torque_penalty_of(x: ArrayLike, task: Task) -> float:
    """
    Return eq. (2)'s torque penalty of normalized genome x on `task` (0 without one).

    Args:
        x: the normalized genome, shape (genome_spec(task).size,), values in [0, 1].
        task: a core.task.Task.

    Returns:
        The penalty added to every objective (the objectives' units: m or rad).
    """
    design = _TaskContext.of(task).genome_spec().decode(np.asarray(x, dtype=float))
    return design_torque_penalty(task, design)


def evaluate_design(design: Design, task: Task, worlds: Optional[Sequence[WorldState]] = None,
                    simulator: Optional[Any] = None, on_frame: Optional[OnWorld] = None,
                    frame_every: int = 1, on_world: Optional[OnWorld] = None,
                    share: Optional[Tuple[int, int]] = None) -> Evaluation:
    """
    Return the Evaluation of a Design on `task`, as `evaluate` does for a genome.

    Args:
        design: the decoded design (core.design.Design): hand and controller.
        task: a core.task.Task.
        worlds: WorldStates to evaluate on, as for `evaluate`; None: the task's.
        simulator: a core.sim Simulator or MujocoSimulator; None: the process-wide one of
            the task's engine (physics.engine).
        on_frame: for replay, `on_frame(step, simulator)` is called at the rollout's frames
            (see Simulator.rollout).
        frame_every: the steps (of task.time_step s) between two frames.
        on_world: `on_world(index, simulator)` is called before each world's rollout.
        share: (first, end), the worlds simulated and scored, as for `evaluate`.

    Returns:
        The Evaluation, as `evaluate` returns it.

    A task in several engines (physics.engines) is evaluated on the same worlds in each of
    them, in the list's order, and scored by `across_engines`; a `simulator` given simulates
    in its own engine only.
    """
    engines = task.physics.engines
    if simulator is not None or len(engines) == 1:
        return _evaluate_in(simulator or shared_simulator(task.physics.engine), design, task,
                            worlds, on_frame, frame_every, on_world, share)
    return across_engines(task, [
        _evaluate_in(shared_simulator(engine), design, task, worlds, on_frame, frame_every,
                     on_world, share) for engine in engines])


def across_engines(task, evaluations):
    """
    Return the Evaluation of a candidate in several engines from its Evaluation in each.

    Args:
        task: the Task; physics.engine_aggregate chooses the objectives: 'mean', the mean of
            the engines' objectives (each with the torque penalty, eq. 2), or 'worst', per
            objective the largest (the worse engine's error, objective by objective, not the
            engine of the worse fitness). A design that starts in collision in any engine
            scores COLLISION_PENALTY in every objective and counts as a collision.
        evaluations: Evaluations of one candidate on the same worlds, one per engine, in
            task.physics.engines' order.

    Returns:
        an Evaluation whose fitness is that of its objectives, whose per-world arrays
        (world_objectives, initial_errors, final_errors, final_poses) hold the engines' rows
        stacked engine by engine (rows k * worlds to (k + 1) * worlds - 1: engine k), whose
        unstable worlds and simulated time are summed and outcomes (shares) averaged.
    """
    each = np.array([evaluation.objectives for evaluation in evaluations])
    collision = any(evaluation.collision for evaluation in evaluations)
    if collision:
        objectives = np.full(each.shape[1], COLLISION_PENALTY)
    elif task.physics.engine_aggregate == 'worst':
        objectives = each.max(axis=0)
    else:
        objectives = each.mean(axis=0)

    def rows(name):
        return np.concatenate([getattr(evaluation, name) for evaluation in evaluations])

    first = evaluations[0]
    outcomes = (np.mean([evaluation.outcomes for evaluation in evaluations], axis=0)
                if len(first.outcomes) else first.outcomes)
    return Evaluation(objectives=objectives, objective_names=first.objective_names,
                      fitness=weighted_fitness(objectives, task.objective_weights),
                      world_objectives=rows('world_objectives'), collision=collision,
                      unstable_worlds=sum(e.unstable_worlds for e in evaluations),
                      simulated_time=float(sum(e.simulated_time for e in evaluations)),
                      initial_errors=rows('initial_errors'), final_errors=rows('final_errors'),
                      final_poses=rows('final_poses'), outcome_names=first.outcome_names,
                      outcomes=outcomes)


def _evaluate_in(simulator, design, task, worlds, on_frame, frame_every, on_world, share):
    """Return the Evaluation of a Design on `task` simulated by `simulator` (one engine)."""
    context = _TaskContext.of(task)
    every_state, every_initial = context.objects(worlds)
    first, end = (0, len(every_state)) if share is None else share
    states, initial = every_state[first:end], every_initial[first:end]
    schedule = context.schedule
    model = hand_model(design.hand, task.hand)
    policy = make_policy(task.policy, design.controller, model.initial_angles,
                         task.time_step)
    penalty = design_torque_penalty(task, design)
    simulator.build(task, model)
    kind = task.object_spec.shape
    objects = [(state, simulator.object_shape(state, kind)) for state in every_state]
    num_objectives = schedule.num_objectives
    watch = OutcomeWatch(context.outcome_names, states)
    if simulator.start_collisions(objects):
        world_values = np.full((len(states), num_objectives), COLLISION_PENALTY)
        starts = np.array([(*state.position, *state.orientation) for state in states],
                          dtype=float).reshape(len(states), 7)
        return _evaluation(task, combine_worlds(world_values, collision=True), world_values,
                           True, 0, 0.0, initial.copy(), initial.copy(), starts, watch)
    world_values = np.empty((len(states), num_objectives))
    final = np.empty((len(states), 2))
    final_poses = np.empty((len(states), 7))
    unstable_worlds, steps = 0, 0
    for index, (state, shape) in enumerate(objects[first:end]):
        if on_world is not None:
            on_world(index, simulator)
        result = simulator.rollout(state, shape, policy, schedule, on_frame, frame_every,
                                   watch.on_end(index))
        steps += result.steps
        if result.unstable:
            unstable_worlds += 1
            world_values[index] = UNSTABLE_PENALTY
        else:
            world_values[index] = result.trace.objective_values()
        final[index] = schedule.pose_errors(result.final_position, result.final_orientation,
                                            state)
        final_poses[index] = (*result.final_position, *result.final_orientation)
    objectives = combine_worlds(world_values, penalty, fraction=task.worlds.worst_fraction)
    return _evaluation(task, objectives, world_values, False, unstable_worlds,
                       steps * task.time_step, initial.copy(), final, final_poses, watch)


def _evaluation(task, objectives, world_values, collision, unstable_worlds, simulated_time,
                initial, final, final_poses, watch):
    return Evaluation(objectives=np.asarray(objectives, dtype=float),
                      objective_names=tuple(task.objective_names),
                      fitness=weighted_fitness(objectives, task.objective_weights),
                      world_objectives=world_values, collision=bool(collision),
                      unstable_worlds=int(unstable_worlds),
                      simulated_time=float(simulated_time), initial_errors=initial,
                      final_errors=final, final_poses=final_poses,
                      outcome_names=watch.names, outcomes=watch.shares())
