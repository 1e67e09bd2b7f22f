"""
`hand-codesign check TASK [--json]`: validate a task file and show what a run of it would do.

A run of a preset costs hours; this answers in a second, before any simulation, with what the
run will search and meet: the genome (names, bounds in SI units), the objectives, every
training world (randomized values, the object's start pose and its goals in world
coordinates), the hierarchy's structures, and the physics steps per evaluation and for the
whole budget. `--seed`, `--iterations`, `--population` and `--world-states` act as in
`hand-codesign run`. The values come from `core.run.preview`; `--json` prints them as one JSON
object on standard output (floats exact), and nothing else goes there. A task a run would
refuse exits 2 with one line naming the file.
"""

import json
import re
import sys
import textwrap

from hand_codesign.core.run.preview import preview
from hand_codesign.core.run.runs import load_run_task
from hand_codesign.core.search.hierarchy import HierarchyError
from hand_codesign.core.search.optimizers import OptimizerError
from hand_codesign.core.task import TaskError
from hand_codesign.errors import UserError

OVERRIDES = ('iterations', 'population', 'world_states')
# What wrapping must not split: a bracketed list, a number and its unit.
_UNBROKEN = re.compile(r'\[[^\]]*\]|\d (?:s|m|rad)\b')


def check_command(arguments):
    """Validate the task and print what a run would do; return 0."""
    summary = task_preview(arguments)
    if arguments.json:
        sys.stdout.write(json.dumps(summary, allow_nan=False) + '\n')
    else:
        print(describe(summary))
    return 0


def task_preview(arguments):
    """Return core.run.preview of the task a run with these arguments uses, or raise UserError."""
    for flag in OVERRIDES:
        value = getattr(arguments, flag)
        if value is not None and value < 1:
            raise UserError(f'--{flag.replace("_", "-")}: expected a positive number, '
                            f'got {value}')
    if arguments.seed is not None and arguments.seed < 0:
        raise UserError(f'--seed: expected 0 or more, got {arguments.seed}')
    try:
        task = load_run_task(arguments.task, arguments.seed, arguments.iterations,
                             arguments.population, arguments.world_states)
    except TaskError as error:
        raise UserError(str(error)) from None
    try:
        return preview(task)
    except TaskError as error:
        raise UserError(str(error)) from None
    except HierarchyError as error:
        raise UserError(f'{task.source}: hierarchy: {error}') from None
    except OptimizerError as error:
        raise UserError(f'{task.source}: optimizer: {error}') from None


# ---------------------------------------------------------------- the text


def describe(summary):
    """Return the text of a preview: budget, genome, objectives, goals and worlds."""
    sections = [header(summary), physics(summary), genome_table(summary),
                objective_lines(summary), worlds_text(summary)]
    return '\n\n'.join(section for section in sections if section)


def header(summary):
    budget = summary['budget']
    lines = [f'task {summary["task"]} ({summary["source"]}): valid']
    if summary['description']:
        lines.append(wrap(summary['description'].strip(), '  '))
    start = budget['structures'][0]['start']
    lines.append(wrap(f'budget: {budget["algorithm"]}, {budget["iterations"]} iterations x '
                      f'{budget["population"]} candidates, {budget["world_states"]} world '
                      f'states, seed {summary["seed"]}; the search starts at the {start} with '
                      f'step size {budget["initial_sigma"]:g} (normalized genome)'))
    archive = budget['archive']
    if archive:
        axes = ' x '.join(
            f'{name} [{low:.4g}, {high:.4g}]{" " + unit if unit else ""}' for name, unit, (
                low, high) in zip(archive['descriptors'], archive['units'], archive['ranges']))
        sizes = sorted(set(archive['emitters']))
        lines.append(wrap(f'archive: {archive["cells"][0]} x {archive["cells"][1]} cells over '
                          f'{axes}; {len(archive["emitters"])} CMA-ES emitters of '
                          f'{" or ".join(map(str, sizes))} candidates, learning rate '
                          f'{archive["learning_rate"]:g}'))
    if summary['changed']:
        lines.append(wrap('settings away from their defaults (docs/TASK.md): ' + ', '.join(
            f'{name} {_setting(value)}' for name, value in summary['changed'].items())))
    if summary['hierarchy']:
        check = budget['structures'][0]['check_world_states']
        grown = summary['hierarchy_grown']
        path = summary['hierarchy'][:len(summary['hierarchy']) - len(grown['choices'])]
        then = (f', then {grown["count"]} of {" ".join(str(s) for s in grown["choices"])}: a '
                'finger added to the best checked structures of the most fingers'
                if grown['choices'] else '')
        lines.append(wrap('hierarchy: ' + ' -> '.join(str(s) for s in path) + then
                          + f' (each structure runs the whole budget {budget["repeats"]} '
                          'times with its own seed, then the better best design is checked on '
                          f'{check} held-out world states, disjoint from the training worlds)'))
    else:
        lines.append(f'hand structure: {summary["structure"]} (fixed)')
    return '\n'.join(lines)


def engines(summary):
    """Return the text that names a task's engines when it has several, else ''."""
    names = summary['settings'].get('physics.engines') or []
    return f' x {len(names)} engines ({", ".join(names)})' if len(names) > 1 else ''


def physics(summary):
    budget = summary['budget']
    rollout = summary['steps_per_rollout']
    step = summary['time_step']
    lines = [wrap(f'physics steps: {rollout:,} per rollout ({step:g} s each, '
                  f'{summary["rollout_time"]:g} s: a rollout ends at the last goal; task '
                  f'duration {summary["duration"]:g} s)'),
             f'  per evaluation: {budget["world_states"]} worlds x {rollout:,}'
             f'{engines(summary)} = {summary["steps_per_evaluation"]:,}']
    early = summary['early_termination']
    if early is None:
        lines.append('  no early termination: every rollout runs to its last goal unless its '
                     'simulation becomes unstable')
    else:
        lines.append(wrap(f'early termination can shorten a rollout: checked '
                          f'{early["checks_per_second"]:g} times per simulated second, margins '
                          f'{early["distance"]:g} m and {early["angle"]:g} rad', '  '))
    rows = [['structure', 'genes', 'evaluations', 'rollouts', 'physics steps']]
    for entry in budget['structures']:
        rows.append([str(entry['structure']) + (' *' if entry.get('grown') else ''),
                     str(entry['genome_size']),
                     f'{entry["evaluations"]:,}', f'{entry["rollouts"]:,}',
                     f'{entry["physics_steps"]:,}'])
    if len(budget['structures']) > 1:
        rows.append(['all', '', f'{budget["evaluations"]:,}', f'{budget["rollouts"]:,}',
                     f'{budget["physics_steps"]:,}'])
    lines.append(wrap(f'whole budget ({budget["iterations"]} x {budget["population"]} x '
                      f'{summary["steps_per_evaluation"]:,} per structure'
                      + (f', {budget["repeats"]} times, plus each check of the hierarchy; * '
                         f'grown, the {summary["hierarchy_grown"]["count"]} costliest counted'
                         if summary['hierarchy'] else '')
                      + (', stage 1 on the nominal world, then stage 2'
                         if budget['stages'] == 2 else '')
                      + (", plus the final check of the resampled generations' best designs"
                         if summary['world_scoring']['resample'] == 'generation' else '')
                      + f'): {budget["physics_steps"]:,} steps, '
                      f'{budget["simulated_time"]:,.0f} s simulated', '  '))
    lines.append(indent(table(rows), 4))
    lines.append(wrap('at most, as a run can do less: ' + '; '.join(budget['may_end_early'])
                      + '.', '  '))
    return '\n'.join(lines)


def genome_table(summary):
    genes = summary['genome']
    what = 'the first structure of the hierarchy, ' if summary['hierarchy'] else ''
    title = (f'genome: {len(genes)} values ({what}structure {summary["structure"]}; bounds in '
             'SI units, the optimizer folds each into [0, 1])')
    if not genes:
        return title
    rows = [['name', 'low', 'high', 'unit']]
    rows += [[gene['name'], _number(gene['low']), _number(gene['high']),
              '-' if gene['unit'] == '1' else gene['unit']] for gene in genes]
    return wrap(title) + '\n' + indent(table(rows), 2)


def objective_lines(summary):
    lines = [f'objectives ({summary["distance"]} distance for positions, angles in rad):']
    for objective in summary['objectives']:
        if objective['trajectory']:
            when = (f'trajectory from {objective["start_time"]:g} s to {objective["time"]:g} s,'
                    f' {objective["samples"]} samples')
        else:
            when = f'at {objective["time"]:g} s'
        lines.append(f'  {objective["name"]}: {when}, weight {objective["weight"]:g}')
    if any(objective['trajectory'] for objective in summary['objectives']):
        lines.append(wrap('a trajectory objective also scores goals interpolated between '
                          'its goal and the previous one (goal 0: the start; positions '
                          'linearly, orientations by slerp) every '
                          f'{1 / summary["samples_per_second"]:g} s; --json lists every '
                          'sample of every world', '  '))
    return '\n'.join(lines)


CONTACT_UNITS = {'stiffness': 'N/m', 'damping': 'N s/m', 'restitution': 'a coefficient'}


def worlds_text(summary):
    worlds = summary['worlds']
    ranges = summary['randomization']['ranges']
    names = [name for name, (low, high) in ranges.items() if high > low]
    varied = ', '.join(f'{name} [{_number(ranges[name][0])}, {_number(ranges[name][1])}]'
                       for name in names)
    axis = _vector(summary['randomization']['orientation_axis'])
    lines = [wrap(f'worlds: {len(worlds)} training worlds of seed {summary["seed"]}; '
                  f'randomized: {varied or "nothing"} (position: m added; orientation: rad '
                  f'about {axis}; friction: added; scale, mass: factors)')]
    contact = list(worlds[0].get('contact', {})) if worlds else []  # physics.contact
    if contact:
        units = ', '.join(f'{name} ({CONTACT_UNITS[name]})' for name in contact)
        lines.append(wrap(f'  each world also draws its contact (physics.contact): {units}'))
    rows = [['world'] + names + contact + ['start position (m)', 'start orientation (x y z w)']]
    for world in worlds:
        rows.append([str(world['index'])] + [f'{world[name]:.4g}' for name in names]
                    + [f'{world["contact"][name]:.4g}' for name in contact]
                    + [_vector(world['start']['position']),
                       _vector(world['start']['orientation'])])
    lines.append(indent(table(rows), 2))
    lines.append(scoring_text(summary))
    if summary['goals_relative_to_start']:
        lines.append("goals in world coordinates (relative to the start: each world's goals "
                     'move and turn with its start):')
        for world in worlds:
            lines.extend(f'  world {world["index"]}, {goal_text(goal)}'
                         for goal in world['goals'])
    elif worlds:
        lines.append('goals in world coordinates (absolute: the same in every world):')
        lines.extend(f'  {goal_text(goal)}' for goal in worlds[0]['goals'])
    return '\n'.join(lines)


def scoring_text(summary):
    """Return how the worlds score a candidate and which worlds it meets (task `worlds`)."""
    scoring = summary['world_scoring']
    if scoring['aggregate'] == 'worst':
        how = (f'each objective is the mean over its worst {scoring["fraction"]:g} of the '
               'worlds (CVaR, worlds.aggregate: worst)')
    else:
        how = 'each objective is the mean over the worlds (eq. 5)'
    if scoring['resample'] == 'generation':
        which = ('each generation meets a fresh draw of as many worlds (worlds.resample: '
                 'generation); the result is the best, on the worlds above (not trained '
                 f'on), of the best designs of the last {scoring["final_check"]} generations')
    else:
        which = 'every candidate meets the training worlds above'
    race = scoring.get('racing')
    if race is not None:
        which += (f', in {len(race["bounds"]) - 1} rounds (worlds {race["bounds"]}); after each '
                  'a candidate stops once it cannot be among the mu CMA-ES selects (racing, '
                  f'a world\'s weighted objectives within {race["range"]:g}, delta '
                  f'{race["delta"]:g})')
    return wrap(f'scoring: {how}; {which}')


def goal_text(goal):
    parts = []
    if goal['position'] is not None:
        parts.append(f'position {_vector(goal["position"])} m')
    if goal['orientation'] is not None:
        parts.append(f'orientation {_vector(goal["orientation"])}')
    return f'{goal["time"]:g} s: ' + ', '.join(parts) + f' ({", ".join(goal["objectives"])})'


def wrap(text, prefix=''):
    """Return text wrapped to 99 columns, every line after the first indented two more."""
    kept = _UNBROKEN.sub(lambda match: match.group(0).replace(' ', '\0'), text)
    return textwrap.fill(kept, width=99, initial_indent=prefix, subsequent_indent=prefix + '  ',
                         break_on_hyphens=False).replace('\0', ' ')


def table(rows):
    """Return rows as aligned text: the first column left, the others right."""
    widths = [max(len(row[index]) for row in rows) for index in range(len(rows[0]))]
    return '\n'.join('  '.join(cell.ljust(width) if index == 0 else cell.rjust(width)
                               for index, (cell, width) in enumerate(zip(row, widths))).rstrip()
                     for row in rows)


def indent(text, spaces):
    return '\n'.join(' ' * spaces + line for line in text.split('\n'))


def _setting(value):
    """Return a setting as YAML writes it: true, 0.25, [1, 2]."""
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, list):
        return '[' + ', '.join(_setting(item) for item in value) + ']'
    return f'{value:g}' if isinstance(value, float) else str(value)


def _number(value):
    return f'{value:.6g}'


def _vector(values):
    """Return values with 5 digits, rounding-error residues (below 1e-12) shown as 0."""
    return '[' + ', '.join(f'{value if abs(value) > 1e-12 else 0.0:.5g}' for value in values) + ']'
