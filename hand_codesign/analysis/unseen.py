"""
`analyze BAG --unseen N`: a run's best design on N worlds it never trained on.

The same measures as a reproduce campaign's (hand_codesign.campaign, core.experiments.measures),
for one bag: the share of worlds within each tolerance of the task's goals, the median and
90th percentile of the error, whether the design found its joint limits, and where in each
randomized quantity's range it fails (bands of equal width).
"""

import dataclasses

from hand_codesign.analysis.records import final_design
from hand_codesign.analysis.tables import error_text, percent
from hand_codesign.core.experiments.measures import (ALONG_X_5MM, ALONG_Y_5MM, measure_worlds,
                                                     ORIENTATION_01, PLANE_5MM, POSE,
                                                     POSITION_5MM, shares_in_bands, summarize,
                                                     Tolerance, unseen_world_states)
from hand_codesign.core.experiments.robustness import world_values
from hand_codesign.core.sim.worlds import QUANTITIES
import numpy as np

BANDS = 3  # bands of each randomized quantity's range in `analyze --unseen`


def unseen_tolerances(task):
    """
    Return the Tolerances that `analyze --unseen` reports for a task, those of reproduce.

    Only the errors of the goals the task has: without a position goal the box's distance
    from its start would read as an error ("final position irrelevant", Task 6).
    """
    position = (PLANE_5MM, POSITION_5MM, ALONG_X_5MM, ALONG_Y_5MM) if task.goals.position else ()
    orientation = (ORIENTATION_01,) if task.goals.orientation else ()
    pose = (POSE,) if position and orientation else ()
    return position + orientation + pose


def scored_tolerance(task):
    """
    Return the Tolerance of the error the task's goals score, for its bands by world.

    The last position goal's: along x or y when it measures one axis of the plane (the Task
    5 presets), else in the plane; without a position goal the orientation's.
    """
    if not task.goals.position:
        return ORIENTATION_01
    axes = set(task.goals.position[-1].axes) - {'z'}
    return {frozenset('x'): ALONG_X_5MM, frozenset('y'): ALONG_Y_5MM}.get(frozenset(axes),
                                                                          PLANE_5MM)


def world_bands(task, worlds, measures, tolerance, bands=BANDS):
    """
    Return {quantity: [(low, high, worlds, share within)]} over each randomized quantity.

    The range of each quantity the task randomizes is cut into `bands` of equal width: the
    shares tell where in that range the design fails (Task 6: the smallest boxes).
    """
    within = measures.errors[tolerance.kind] < tolerance.limit
    values = np.array([world_values(world) for world in worlds]).reshape(len(worlds), -1)
    return {name: shares_in_bands(values[:, QUANTITIES.index(name)], within,
                                  np.linspace(bounds.lower, bounds.upper, bands + 1))
            for name, bounds in task.randomization.quantities() if bounds.width > 0}


def band_lines(bands, tolerance):
    """Return the Markdown table of world_bands' shares, a row per quantity."""
    count = max((len(row) for row in bands.values()), default=0)
    lines = [f'Share of the worlds with {tolerance.describe()}, by where each randomized '
             f'quantity fell in its range ({count} bands of equal width, SI units; worlds in '
             'brackets):', '',
             '| quantity | ' + ' | '.join(f'band {index + 1}' for index in range(count)) + ' |',
             '|---|' + '---|' * count]
    for name, row in bands.items():
        lines.append(f'| {name} | ' + ' | '.join(
            f'[{low:.3g}, {high:.3g}]: {percent(share) if worlds else "-"} ({worlds})'
            for low, high, worlds, share in row) + ' |')
    return lines


def behaviours(measures):
    """
    Return [(what the hand did, (worlds,) bool)]: each world in exactly one of them.

    From the rollouts' touch and limit flags (core.experiments.measures): started in collision,
    never touched the object, touched it and let it go, holds it at the end with a finger on a
    joint limit, holds it off its limits.
    """
    collided = measures.collisions
    touched, touching = measures.touched, measures.touching
    on_limit = measures.limit_contacts
    return [('starts in collision', collided),
            ('never touches the object', ~collided & ~touched),
            ('touches it, then lets it go', ~collided & touched & ~touching),
            ('holds it at the end, a finger on a joint limit', ~collided & touching & on_limit),
            ('holds it at the end, off its limits', ~collided & touching & ~on_limit)]


def behaviour_lines(measures, tolerance):
    """Return Markdown lines: what the hand did in the worlds, and how often each succeeds."""
    if measures.touched is None:
        return []
    within = measures.errors[tolerance.kind] < tolerance.limit
    lines = [f'What the hand did (the share of the worlds; of those, the share with '
             f'{tolerance.describe()}):', '', '| what the hand did | worlds | of them within |',
             '|---|---|---|']
    for name, worlds in behaviours(measures):
        if worlds.any():
            lines.append(f'| {name} | {percent(float(np.mean(worlds)))} | '
                         f'{percent(float(np.mean(within[worlds])))} |')
    return lines + ['']


def unseen_report(bag, count, processes=1, engine=None):
    """
    Return (Markdown lines, JSON record) of a run's best design on `count` unseen worlds.

    `engine` ('pybullet' or 'mujoco') measures it in that physics engine instead of the run's
    (a design's transfer to the other engine). A run in several engines (physics.engines) is
    measured in each of them on the same worlds: a table of the share within each tolerance
    per engine, then each engine's report; its record is {'bag', 'seed', 'unseen_worlds',
    'run_engine', 'engines': {engine: that engine's record}}.

    The same measures as a reproduce campaign's: for each error of the task's goals
    (unseen_tolerances) the share of worlds within 5 mm or 0.1 rad, its median and p90, and
    whether the design found its joint limits (core.experiments.measures) on the error its goals
    score.
    """
    task, x, structure = final_design(bag)
    found_in = ','.join(task.physics.engines)
    engines = (engine,) if engine else task.physics.engines
    reports = [engine_report(bag, task.replace(physics=task.physics.with_engines((name,))), x,
                             structure, count, processes, found_in) for name in engines]
    if len(reports) == 1:
        return reports[0]
    lines = [f'## On {count} unseen worlds, in each engine of the run', '',
             f'The best design (structure {list(structure)}) on the same {count} unseen worlds '
             f'in each engine the run evaluated in ({", ".join(engines)}):', '',
             '| error | ' + ' | '.join(f'within, {name}' for name in engines) + ' |',
             '|---|' + '---|' * len(engines)]
    records = {name: record for name, (_, record) in zip(engines, reports)}
    for index, summary in enumerate(reports[0][1]['summaries']):
        lines.append(f"| {Tolerance(**summary['tolerance']).describe()} | " + ' | '.join(
            percent(records[name]['summaries'][index]['within']) for name in engines) + ' |')
    lines.append('')
    for name, (part, _) in zip(engines, reports):
        lines += [f'#{part[0]}, in {name}'] + part[1:]
    return lines, {'bag': str(bag), 'seed': task.seed, 'unseen_worlds': count,
                   'run_engine': found_in, 'engines': records}


def engine_report(bag, task, x, structure, count, processes, found_in):
    """Return unseen_report's (lines, record) of design x measured in task's one engine."""
    worlds = unseen_world_states(task, count)
    measures = measure_worlds(x, task, worlds, processes)
    summaries = [summarize(measures, tolerance) for tolerance in unseen_tolerances(task)]
    lines = [f'## On {count} unseen worlds', '',
             f'The best design (structure {list(structure)}) on {count} worlds drawn from '
             f'another stream of seed {task.seed} than the training worlds, simulated with '
             f'{task.physics.engine} (the run used {found_in}).', '',
             '| error | within | median | p90 | median at the start |', '|---|---|---|---|---|']
    for summary in summaries:
        tolerance = summary.tolerance
        lines.append(f'| {tolerance.describe()} | {percent(summary.within)} | '
                     f'{error_text(summary.median, tolerance)} | '
                     f'{error_text(summary.p90, tolerance)} | '
                     f'{error_text(summary.initial_median, tolerance)} |')
    first = summaries[0]
    scored = scored_tolerance(task)
    judged = summarize(measures, scored)
    lines += ['', f'Within {scored.describe()} while resting on a joint limit it reached, '
                  f'touching the object: {percent(judged.limit_success_share)} of the worlds, '
                  f'{percent(judged.limit_share_of_successes)} of those within; joint limits '
                  f'found (at least half of those within and a quarter of all): '
                  f'{"yes" if judged.joint_limits_found else "no"}. Resting on a joint limit '
                  f'while touching, whatever the outcome: {percent(first.limit_contact_share)} '
                  f'of the worlds. Start collisions: {percent(first.collision_share)} of the '
                  'worlds. Every world runs the whole motion, with no early termination.', '']
    lines += behaviour_lines(measures, scored)
    bands = world_bands(task, worlds, measures, scored)
    lines += band_lines(bands, scored)
    record = {'bag': str(bag), 'seed': task.seed, 'unseen_worlds': count,
              'engine': task.physics.engine, 'run_engine': found_in,
              'summaries': [summary.as_dict() for summary in summaries],
              'bands': {'tolerance': dataclasses.asdict(scored), 'quantities': bands},
              'behaviours': {name: float(np.mean(worlds)) for name, worlds in behaviours(measures)}
              if measures.touched is not None else {}}
    return lines, record
