"""
What a run of a task would do, worked out without simulating anything (`hand-codesign check`).

`preview(task)` builds what a run builds before its first rollout (the genome of every hand
structure, the optimizer of each, the goal schedule, the world states) and returns it as one
mapping of plain lists, numbers and strings, ready for JSON::

    genome              [{name, low, high, unit}]: the optimized values of the task's structure
                        (the hierarchy's first), bounds in SI units
    objectives          [{name, kind, time, start_time, trajectory, samples, weight}]
    worlds              every training world of the task's seed: its randomized values (the
                        names of core.sim.worlds.QUANTITIES), `object` (mass kg, friction, size m),
                        `start` {position, orientation} and `goals` [{time, position or None,
                        orientation or None, objectives}] in world coordinates, and `samples`:
                        every goal sample a trajectory objective scores, also in world
                        coordinates
    world_scoring       {aggregate, fraction, resample, final_check, racing}: the task's
                        `worlds` (the mean or the worst fraction of the worlds; fixed or
                        resampled); racing None, or {rounds, range, delta, bounds}: the world
                        indices where a generation's rounds start and end (core.search.racing)
    settings            every key of the task file by its dotted name, its value as read
                        (defaults filled in; core.task.schema, docs/TASK.md)
    changed             those of `settings` whose value is not their key's default
    hierarchy           the structures a hierarchy search may visit, e.g. [[1], [2], [1, 1]],
                        in order: its path, then the structures it may grow a finger to
                        ([1, 1, 3]); [] for a fixed structure
    hierarchy_grown     {count, choices}: of the grown structures (`choices`, the end of
                        `hierarchy`) a run visits `count`, those grown from the best checks
    steps_per_rollout   physics steps of one world's rollout (it ends at the last goal)
    steps_per_evaluation  worlds x steps_per_rollout: one candidate (x its engines, when the
                        task evaluates in several: physics.engines)
    budget              algorithm, iterations, population, world states, and per structure and
                        in all the evaluations, rollouts and physics steps the budget allows
                        (a hierarchy optimizes each structure `repeats` times; a two-stage
                        task runs stage 1 on the nominal world and stage 2 on its worlds, each
                        with the whole budget; the total counts the costliest grown ones;
                        rollouts and steps count each engine of physics.engines)

Counts are what the budget allows; a run can do less (`budget.may_end_early` says why): early
termination and unstable worlds cut rollouts, a design starting in collision is not simulated,
CMA-ES stops on pycma's own criteria and a hierarchy stops at the first structure that meets
its thresholds. Every float is the one the core computes (JSON keeps it exactly). Errors a run
would meet before simulating (a bad task file, a genome or hierarchy that cannot be built, an
optimizer that refuses the budget) raise TaskError, HierarchyError or OptimizerError here.
"""

import dataclasses

from hand_codesign.core.experiments.robustness import world_values
from hand_codesign.core.search.factory import make_optimizer
from hand_codesign.core.search.hierarchy import bottom_up_path
from hand_codesign.core.search.hierarchy import grown_choices
from hand_codesign.core.search.hierarchy import GROWN_FROM
from hand_codesign.core.search.hierarchy import grows_fingers
from hand_codesign.core.search.hierarchy import REPEATS
from hand_codesign.core.search.racing import round_bounds
from hand_codesign.core.sim.events import EventPlan
from hand_codesign.core.sim.objectives import goal_schedule
from hand_codesign.core.sim.worlds import object_state, QUANTITIES, world_states
from hand_codesign.core.task.genome import genome_spec
from hand_codesign.core.task.parts import QD_ALGORITHMS
from hand_codesign.core.task.schema import away_from_defaults, settings

KINDS = ('position', 'orientation')

# Unit of a gene by the last part of its name (core.task.genome's naming scheme).
_UNITS = (('hand.base_position_', 'm'), ('hand.base_yaw', 'rad'), ('.position_x', 'm'),
          ('.position_z', 'm'), ('.length', 'm'), ('_angle', 'rad'), ('_limit', 'rad'),
          ('controller.target.', 'rad'),
          ('controller.torque.', 'N m'), ('controller.kp.', 'N m/rad'),
          ('controller.kd.', 'N m s/rad'), ('hand.friction', '1'))


def preview(task):
    """Return what a run of `task` would do as one JSON-ready mapping (see the module doc)."""
    schedule = goal_schedule(task)
    path = hierarchy_path(task)
    grown = grown_structures(task, path)
    structures, grown_budgets = structure_budgets(task, path, grown)
    rollout = rollout_steps(task)
    steps_per_evaluation = task.num_world_states * rollout * len(task.physics.engines)
    return {
        'task': task.name,
        'source': task.source,
        'description': task.description,
        'seed': task.seed,
        'time_step': task.time_step,
        'duration': task.duration,
        'structure': list(task.structure),
        'genome': structures[0]['genome'],
        'objectives': objectives(task, schedule),
        'goals_relative_to_start': task.goals.relative_to_start,
        'distance': task.goals.distance,
        'samples_per_second': task.goals.samples_per_second,
        'randomization': randomization(task),
        'worlds': worlds(task, schedule),
        'world_scoring': world_scoring(task),
        'hierarchy': [list(structure) for structure in path + grown],
        'hierarchy_grown': {'count': min(GROWN_FROM, len(grown)),
                            'choices': [list(structure) for structure in grown]},
        'steps_per_rollout': rollout,
        'rollout_time': rollout * task.time_step,
        'steps_per_evaluation': steps_per_evaluation,
        'early_termination': early_termination(task),
        'budget': budget(task, structures, grown_budgets),
        'settings': settings(task),
        'changed': away_from_defaults(settings(task), type(task)),
    }


def run_budget(task):
    """Return the budget of a whole run of `task` (as `preview(task)['budget']`)."""
    path = hierarchy_path(task)
    return budget(task, *structure_budgets(task, path, grown_structures(task, path)))


def structure_budgets(task, path, grown):
    """Return the budgets of the structures searched and of those a finger may be grown to."""
    structures = [structure_budget(task, structure, path) for structure in
                  (path or [tuple(task.structure)])]
    return structures, [dict(structure_budget(task, structure, path), grown=True)
                        for structure in grown]


def hierarchy_path(task):
    """Return the structures a hierarchy search visits (as HierarchySearch does), or []."""
    hierarchy = task.hierarchy
    if hierarchy is None:
        return []
    return bottom_up_path(hierarchy.start, hierarchy.stop_structure, hierarchy.max_fingers,
                          hierarchy.max_joints)


def grown_structures(task, path):
    """Return the structures a hierarchy may grow a finger to after its path, or []."""
    if not path or not grows_fingers(task.hierarchy):
        return []
    return grown_choices(path, task.hierarchy.max_joints)


def rollout_steps(task):
    """Return the physics steps of one full rollout, counted as the simulator counts them."""
    return EventPlan(goal_schedule(task), task.time_step).num_steps


def gene_unit(name):
    """Return the SI unit of a gene from its name ('1' for a plain number)."""
    for ending, unit in _UNITS:
        if ending in name:
            return unit
    return ''


def genome(spec):
    """Return [{name, low, high, unit}] of a GenomeSpec."""
    return [{'name': name, 'low': float(low), 'high': float(high), 'unit': gene_unit(name)}
            for name, low, high in zip(spec.names, spec.lower, spec.upper)]


def structure_budget(task, structure, path):
    """
    Return the genome and budget of one structure, building its optimizer as a run does.

    A hierarchy's structure is optimized REPEATS times and costs the check of its best design
    on the evaluation worlds; a two-stage task's stage 1 evaluates on the nominal world only;
    resampled worlds cost the final check of the last generations' best designs.
    """
    structure_task = task.replace(structure=tuple(structure)) if path else task
    spec = genome_spec(structure_task)
    optimizer = make_optimizer(structure_task, spec.size)
    one = structure_task.iterations * structure_task.population
    if path:
        evaluations, rollouts = REPEATS * one, REPEATS * one * structure_task.num_world_states
    elif task.two_stage:
        evaluations, rollouts = 2 * one, one * (1 + structure_task.num_world_states)
    else:
        evaluations, rollouts = one, one * structure_task.num_world_states
    checks = 1 if path else 0
    check_rollouts = task.hierarchy.evaluation_world_states if path else 0
    if task.worlds.resample == 'generation':  # the final check of the resampled generations
        checks = min(task.worlds.final_check, structure_task.iterations)
        rollouts += checks * structure_task.num_world_states
    seeded = optimizer.x0.tolist() != spec.initial_mean().tolist()
    steps = rollout_steps(structure_task)
    engines = len(task.physics.engines)  # every world is rolled out in each engine
    rollouts, check_rollouts = rollouts * engines, check_rollouts * engines
    return {
        'structure': list(structure_task.structure),
        'genome': genome(spec),
        'genome_size': spec.size,
        'start': 'seed design' if seeded else 'centre of the bounds',
        'evaluations': evaluations + checks,
        'rollouts': rollouts + check_rollouts,
        'physics_steps': (rollouts + check_rollouts) * steps,
        'check_world_states': check_rollouts,
    }


def budget(task, structures, grown=()):
    """Return the budget of the run: per structure and in all, with why a run may do less."""
    costliest = sorted(grown, key=lambda entry: -entry['physics_steps'])[:GROWN_FROM]
    totals = {name: sum(entry[name] for entry in list(structures) + costliest)
              for name in ('evaluations', 'rollouts', 'physics_steps')}
    return {
        'algorithm': task.algorithm,
        'iterations': task.iterations,
        'population': task.population,
        'world_states': task.num_world_states,
        'initial_sigma': task.initial_sigma,
        **totals,
        'simulated_time': totals['physics_steps'] * task.time_step,
        'repeats': REPEATS if task.hierarchy is not None else 1,
        'stages': 2 if task.two_stage else 1,
        'structures': [{key: value for key, value in entry.items() if key != 'genome'}
                       for entry in list(structures) + list(grown)],
        'may_end_early': may_end_early(task),
        'archive': archive_preview(task),
    }


def archive_preview(task):
    """Return the archive of a quality-diversity task (cma-mae, cma-me), else None."""
    if task.algorithm not in QD_ALGORITHMS:
        return None
    optimizer = make_optimizer(task, genome_spec(task).size)
    return {'descriptors': list(optimizer.describe.names),
            'units': list(optimizer.describe.units),
            'cells': list(optimizer.cells), 'ranges': [list(r) for r in optimizer.ranges],
            'emitters': list(optimizer.batch_sizes), 'learning_rate': optimizer.learning_rate}


def world_scoring(task):
    """Return the task's `worlds` by key, its racing as one entry (or None) with its rounds."""
    scoring = {name: value for name, value in settings(task.worlds).items()
               if name.partition('.')[0] != 'racing'}
    scoring['racing'] = racing(task)
    return scoring


def racing(task):
    """Return the task's racing over the worlds by key, with its rounds' bounds, or None."""
    spec = task.worlds.racing
    if spec is None:
        return None
    return dict(settings(spec), bounds=list(round_bounds(task.num_world_states, spec.rounds)))


def may_end_early(task):
    """Return why a run may simulate less than its budget, one sentence each."""
    reasons = []
    if task.worlds.racing is not None:
        reasons.append('racing stops a candidate after a round of its worlds once it cannot '
                       'be among the mu that CMA-ES selects')
    if task.early_termination is not None:
        reasons.append('early termination (eq. 6) stops a rollout at a check where a goal '
                       'misses by more than its margin')
    reasons.append('a rollout stops when its simulation becomes unstable')
    reasons.append('a design that starts in collision is not simulated')
    if task.algorithm == 'cma':
        reasons.append("CMA-ES stops before its iterations on pycma's own criteria "
                       '(tolfun, tolx, ...)')
    if task.hierarchy is not None:
        reasons.append('the hierarchy stops at the first structure whose best design meets '
                       'its thresholds')
    return reasons


def early_termination(task):
    """Return the early-termination margins, or None when rollouts always run to the end."""
    spec = task.early_termination
    if spec is None:
        return None
    return {'distance': spec.distance, 'angle': spec.angle,
            'checks_per_second': spec.checks_per_second}


def objectives(task, schedule):
    """Return every objective with its goal's time, window, trajectory flag, samples, weight."""
    goals = list(task.goals.position) + list(task.goals.orientation)
    return [{'name': name, 'kind': name.split('_')[0], 'time': float(end),
             'start_time': float(begin), 'trajectory': goal.trajectory, 'samples': int(size),
             'weight': float(weight)}
            for name, goal, begin, end, size, weight in zip(
                schedule.objective_names, goals, schedule.objective_start_times,
                schedule.objective_end_times, schedule.objective_sizes,
                task.objective_weights)]


def randomization(task):
    """Return {quantity: [low, high]} of the randomized quantities and the rotation axis."""
    spec = task.randomization
    ranges = {name: [bounds.lower, bounds.upper] for name, bounds in spec.quantities()}
    return {'ranges': ranges, 'orientation_axis': list(spec.orientation_axis)}


def worlds(task, schedule):
    """Return every training world: randomized values, object, start, goals and samples."""
    result = []
    for index, world in enumerate(world_states(task)):
        state = object_state(task, world)
        entry = {'index': index}
        entry.update(zip(QUANTITIES, (float(value) for value in world_values(world))))
        entry['object'] = {'mass': state.mass, 'friction': state.friction,
                           'size': list(state.size)}
        if world.contact is not None:  # physics.contact: the parameters this world drew
            entry['contact'] = {name: value for name, value in
                                dataclasses.asdict(world.contact).items() if value is not None}
        entry['start'] = {'position': _floats(state.position),
                          'orientation': _floats(state.orientation)}
        entry['goals'] = world_goals(task, schedule, state)
        entry['samples'] = world_samples(schedule, state)
        result.append(entry)
    return result


def world_goals(task, schedule, state):
    """Return the task's goals in the world of `state`, one entry per goal time."""
    by_time = {}
    for kind in KINDS:
        for index, goal in enumerate(getattr(task.goals, kind)):
            entry = by_time.setdefault(goal.time, {'time': goal.time, 'position': None,
                                                   'orientation': None, 'objectives': []})
            entry[kind] = _world_target(schedule, kind, getattr(goal, kind), state)
            entry['objectives'].append(f'{kind}_{index + 1}')
    return [by_time[time] for time in sorted(by_time)]


def world_samples(schedule, state):
    """Return every goal sample (interpolated and final) in the world of `state`."""
    samples = []
    for name, time, target in schedule.goal_samples():
        kind = name.split('_')[0]
        sample = {'time': float(time), 'objective': name, 'position': None,
                  'orientation': None}
        sample[kind] = _world_target(schedule, kind, target, state)
        samples.append(sample)
    return samples


def _world_target(schedule, kind, target, state):
    position, orientation = schedule.world_goal(
        target if kind == 'position' else None, target if kind == 'orientation' else None,
        state)
    return _floats(position if kind == 'position' else orientation)


def _floats(values):
    return [float(value) for value in values]


__all__ = ['gene_unit', 'hierarchy_path', 'preview', 'rollout_steps', 'run_budget']
