"""
A reproduce campaign's folder, read back: its runs' bags, their measures, tables and figures.

Layout of `--out DIR` for one experiment (`hand_codesign.commands.reproduce` writes it)::

    campaign.json                 experiment, budget and seeds the campaign was started with
    tasks/<configuration>.yaml    the pinned task text each run of the configuration used
    runs/<configuration>-seed<k>/ the run's bag (a normal `hand-codesign run` folder);
    runs/<...>-seed<k>.resume1/   the bag of its continuation after an interruption, and so on
    measures/<run>.json           the run's best design measured on unseen worlds (cache)
    <experiment>.csv, .md, *.png  the tables (a row per configuration) and figures (.svg or
                                  .pdf with `reproduce --format`)

Everything here is recomputed from the bags: delete `measures/` and the tables and run
`reproduce` again, and the same numbers come back (the measures are deterministic).

Measures (core.experiments.measures): each run's final design (the optimizer's choice, the final
GenerationSummary's `best_x`) on the budget's unseen worlds of the run's seed. Per
configuration over its seeds: the unseen worlds of all seeds pooled: the share within the
tolerance, the median and 90th percentile of the error; **joint limits found**: the share of
seeds whose design found them (core.experiments.measures: it ends within the tolerance resting on a
limit it reached, touching the box, in at least half of its successes and a quarter of its worlds);
beside it, the mean share of the worlds that are such limit successes, and the looser
earlier measure (resting on a limit while touching, whatever the outcome).
"""

import json
import pathlib

from hand_codesign.analysis import campaign_figures
from hand_codesign.analysis import records
from hand_codesign.analysis.generations import Generations, generations_from_summaries
from hand_codesign.analysis.tables import write_csv
from hand_codesign.core.experiments.catalog import run_key, seeds_text, training_worlds
from hand_codesign.core.experiments.measures import (DesignMeasures, measure_worlds, summarize,
                                                     unseen_world_states, with_pose_error,
                                                     WorldMeasures)
from hand_codesign.core.task.variant import Variant
from hand_codesign.errors import UserError
import numpy as np

RESUME_MARK = '.resume'


def attempts(runs_dir, key):
    """Return the bag folders of a run in order: the first, then each continuation."""
    runs_dir = pathlib.Path(runs_dir)
    found = [runs_dir / key] if (runs_dir / key).exists() else []
    number = 1
    while (runs_dir / f'{key}{RESUME_MARK}{number}').exists():
        found.append(runs_dir / f'{key}{RESUME_MARK}{number}')
        number += 1
    return found


def next_attempt(runs_dir, key):
    """Return the folder the next attempt of a run writes its bag to."""
    done = attempts(runs_dir, key)
    return pathlib.Path(runs_dir) / (key if not done else f'{key}{RESUME_MARK}{len(done)}')


def finished_bag(runs_dir, key):
    """Return the bag folder holding the run's result, or None while it is unfinished."""
    done = attempts(runs_dir, key)
    if done and (done[-1] / 'result.json').exists():
        return done[-1]
    return None


def final_design(bag):
    """Return (task, normalized genome, structure) of a finished run's best design."""
    record = records.open_run(bag, warn=False)
    summary = records.last_summary(record)
    if summary is not None and summary['final'] and len(np.ravel(summary['best_genome'])):
        structure = tuple(int(joints) for joints in np.ravel(summary['structure']))
        x = np.asarray(summary['best_genome'], dtype=float).ravel()
    else:
        design = records.recorded_design(record, records.best_candidate_id(record))
        structure, x = design.structure, design.x
    return records.run_task_of(record, Variant(structure=tuple(structure or ()))), x, structure


def structure_bests(bags):
    """Return {structure: (fitness, candidate id, bag)} of the best OK evaluation per structure."""
    bests = {}
    for bag in bags:
        record = records.open_run(bag, warn=False)
        candidates = record.candidates
        if not len(candidates):
            continue
        structure_of = {}
        for index, candidate_id in enumerate(np.asarray(candidates['candidate_id']).tolist()):
            structure_of.setdefault(int(candidate_id), tuple(
                int(joints) for joints in np.ravel(candidates['structure'][index])))
        rows = records.evaluation_rows(record)
        for index in np.flatnonzero(rows.ok):
            candidate_id = int(rows.candidate_id[index])
            structure = structure_of.get(candidate_id)
            fitness = float(rows.fitness[index])
            if structure is not None and (structure not in bests
                                          or fitness < bests[structure][0]):
                bests[structure] = (fitness, candidate_id, bag)
    return bests


def world_measures_dict(measures):
    """Return WorldMeasures as JSON values (floats exact)."""
    return {'errors': {kind: values.tolist() for kind, values in measures.errors.items()},
            'initial_errors': {kind: values.tolist()
                               for kind, values in measures.initial_errors.items()},
            'collisions': measures.collisions.tolist(),
            'limit_contacts': measures.limit_contacts.tolist(),
            'limit_reached': measures.limit_reached.tolist()}


def world_measures_of(values):
    """Return the WorldMeasures of world_measures_dict()'s output."""
    return WorldMeasures(
        with_pose_error({kind: np.asarray(errors, dtype=float)
                         for kind, errors in values['errors'].items()}),
        with_pose_error({kind: np.asarray(errors, dtype=float)
                         for kind, errors in values['initial_errors'].items()}),
        np.asarray(values['collisions'], dtype=bool),
        np.asarray(values['limit_contacts'], dtype=bool),
        np.asarray(values['limit_reached'], dtype=bool))


def measure_bag(bag, tolerance, unseen_worlds, processes=1):
    """Return the measures record of a finished run's best design on its unseen worlds."""
    task, x, structure = final_design(bag)
    worlds = unseen_world_states(task, unseen_worlds)
    measures = measure_worlds(x, task, worlds, processes)
    return {'bag': str(bag), 'seed': task.seed, 'structure': list(structure),
            'unseen_worlds': unseen_worlds, 'worlds': world_measures_dict(measures),
            'summary': summarize(measures, tolerance).as_dict()}


def measure_structures(bags, tolerance, unseen_worlds, processes=1):
    """Return {structure text: measures record} of each structure's best design (a hierarchy)."""
    measured = {}
    for structure, (_, candidate_id, bag) in sorted(structure_bests(bags).items()):
        record = records.open_run(bag, warn=False)
        design = records.recorded_design(record, candidate_id)
        task = records.run_task_of(record, Variant(structure=tuple(structure)))
        measures = measure_worlds(design.x, task, unseen_world_states(task, unseen_worlds),
                                  processes)
        measured[structure_text(structure)] = {
            'candidate_id': candidate_id, 'worlds': world_measures_dict(measures),
            'summary': summarize(measures, tolerance).as_dict()}
    return measured


def structure_text(structure):
    """Return a structure as the paper writes it, e.g. '(1,3)'."""
    return '(' + ','.join(str(joints) for joints in structure) + ')'


def cached_measures(path, compute, kinds=()):
    """
    Return the JSON record at path, computing and writing it first if it is missing.

    A record measured before one of the error `kinds` existed is measured again.
    """
    values = read_measures(path, kinds)
    if values is not None:
        return values
    values = compute()
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_suffix('.tmp')
    temporary.write_text(json.dumps(values), encoding='utf-8')
    temporary.replace(path)
    return values


def read_measures(path, kinds=()):
    """
    Return the measures record at path, or None if it must be measured (again).

    A record is measured again when it lacks an error kind, or predates the measures of
    issue 26 (rollouts run to their end, the limit a joint reached): its 'limit_reached'.
    The pose error is derived from the plane and orientation errors, never stored.
    """
    path = pathlib.Path(path)
    if not path.exists():
        return None
    values = json.loads(path.read_text(encoding='utf-8'))
    if 'limit_reached' not in values['worlds']:
        return None
    if any(kind not in values['worlds']['errors'] for kind in kinds if kind != 'pose'):
        return None
    return values


def pooled_row(measured, tolerance):
    """
    Return a configuration's row over seeds from its runs' measures records.

    The seeds' unseen worlds are pooled: share within, median and p90 of the error; joint
    limits found is the share of seeds whose design found them. The share within is also
    given per seed (in seed order): whether a lever works in nearly every seed, or in a few
    very well, is what a pooled share hides.
    """
    kind = tolerance.kind
    errors = np.concatenate([record['worlds']['errors'][kind] for record in measured])
    initial = np.concatenate([record['worlds']['initial_errors'][kind] for record in measured])
    summaries = [DesignMeasures.from_dict(record['summary']) for record in measured]
    found = sum(summary.joint_limits_found for summary in summaries)
    within, within_by_seed = shares_within(measured, tolerance)
    return {'seeds': len(measured), 'worlds': int(len(errors)),
            'within': within, 'within_by_seed': within_by_seed,
            'median': float(np.median(errors)), 'p90': float(np.percentile(errors, 90)),
            'initial_median': float(np.median(initial)),
            'joint_limits_found': found,
            'joint_limits_found_share': found / len(measured),
            'limit_contact_share': float(np.mean([s.limit_contact_share for s in summaries])),
            'limit_success_share': float(np.mean([s.limit_success_share for s in summaries])),
            'collision_share': float(np.mean([s.collision_share for s in summaries]))}


TABLE_COLUMNS = ('experiment', 'configuration', 'preset', 'policy', 'algorithm',
                 'world_states', 'budget', 'iterations', 'population', 'seeds',
                 'unseen_worlds', 'tolerance', 'unit', 'within', 'within_by_seed', 'median',
                 'p90',
                 'initial_median', 'joint_limits_found', 'joint_limits_found_share',
                 'limit_success_share', 'limit_contact_share', 'collision_share')


def error_unit(tolerance):
    """Return the SI unit of a tolerance's error (a pose error counts in its tolerances)."""
    return {'orientation': 'rad', 'pose': 'tolerances'}.get(tolerance.kind, 'm')


def write_table(out, name, rows, also=()):
    """Write <name>.csv (SI units, exact floats) of the rows (dicts), further shares last."""
    names = list(TABLE_COLUMNS) + [column for tolerance in also
                                   for column in (also_column(tolerance),
                                                  also_column(tolerance) + '_by_seed')]
    columns = [[_cell(row[column]) for row in rows] for column in names]
    write_csv(pathlib.Path(out) / f'{name}.csv', names, columns)


def _cell(value):
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, tuple):
        return ' '.join(_cell(item) for item in value)
    text = str(value)
    return '"' + text.replace('"', '""') + '"' if any(c in text for c in ',"\n') else text


def percent(share):
    """Return a share as the tables write it, e.g. '58 %'."""
    return f'{100 * share:.0f} %'


def error_text(value, tolerance):
    """Return an error in the table's unit: mm for distances, rad for angles, x for poses."""
    if tolerance.kind == 'orientation':
        return f'{value:.3f} rad'
    if tolerance.kind == 'pose':
        return f'{value:.2f} x'
    return f'{value * 1000:.1f} mm'


def markdown_table(rows, tolerance, first='configuration', also=()):
    """Return the Markdown table of rows: a line per configuration (or structure)."""
    further = ''.join(f'within ({other.describe()}) | each seed (%) | ' for other in also)
    lines = [f'| {first} | policy | algorithm | training worlds | seeds | unseen worlds | '
             f'within ({tolerance.describe()}) | each seed (%) | {further}median | p90 | '
             'median at the start | limit successes | on a limit, touching (any outcome) | '
             'joint limits found |',
             '|---' * (14 + 2 * len(also)) + '|']
    for row in rows:
        shares = [(row['within'], row['within_by_seed'])] + [
            (row[also_column(other)], row[also_column(other) + '_by_seed']) for other in also]
        lines.append(
            f'| {row[first]} | {row["policy"]} | {row["algorithm"]} | {row["world_states"]} '
            f'| {row["seeds"]} | {row["unseen_worlds"]} | '
            + ''.join(f'{within_percent(pooled)} | {seed_percents(by_seed)} | '
                      for pooled, by_seed in shares)
            + f'{error_text(row["median"], tolerance)} | {error_text(row["p90"], tolerance)} | '
            f'{error_text(row["initial_median"], tolerance)} | '
            f'{percent(row["limit_success_share"])} | {percent(row["limit_contact_share"])} | '
            f'{percent(row["joint_limits_found_share"])} ({row["joint_limits_found"]} of '
            f'{row["seeds"]}) |')
    return '\n'.join(lines) + '\n'


def within_percent(share):
    """
    Return a share within tolerance as the tables write it, e.g. '89.6 %'.

    One decimal: a share of 1,000 worlds is exact to it, and a share below a target (89.6 %
    against 90 %) must not read as reaching it.
    """
    return f'{100 * share:.1f} %'


def seed_percents(shares):
    """Return shares within tolerance by seed as the tables write them, e.g. '19.2 37.0'."""
    return ' '.join(f'{100 * share:.1f}' for share in shares)


def plot_errors(path, groups, tolerance, title, kinds=None):
    """Box plots of the pooled initial and final errors per group (campaign_figures)."""
    campaign_figures.plot_errors(path, groups, tolerance, title, kinds)


def run_generations(bags):
    """Return (evaluations told, best fitness so far) over a run's bags, in order."""
    told, best = [], []
    for bag in bags:
        record = records.open_run(bag, warn=False)
        if not len(record.generation_summaries):
            continue
        names = records.objective_names_of(record)
        generations: Generations = generations_from_summaries(record, len(names))
        told += generations.evaluations.tolist()
        best += generations.best_fitness.tolist()
    return np.asarray(told, dtype=float), np.minimum.accumulate(np.asarray(best, dtype=float))


def convergence_panels(out, experiment, seeds):
    """Return (label, [(seed, (told, best))]) of each configuration with runs of `seeds`."""
    panels = []
    for configuration in experiment.configurations:
        curves = [(seed, run_generations(attempts(out / 'runs', run_key(configuration, seed))))
                  for seed in seeds]
        if any(len(told) for _, (told, _) in curves):  # `--only` leaves the others unrun
            panels.append((f'{configuration.key} ({configuration.algorithm_name})', curves))
    return panels


def seed_band(curves):
    """
    Return (evaluations, 25th percentile, median, 75th percentile) of curves across seeds.

    curves: [(seed, (evaluations told, best fitness so far))]. Each seed's best so far is a
    step function of the evaluations: at every evaluation count any seed told, it is its value
    at the last count told up to there (held after the seed's run ended, which cannot improve
    it); NaN before its first, and left out of the percentiles there.
    """
    told = [np.asarray(values[0], dtype=float) for _, values in curves if len(values[0])]
    best = [np.asarray(values[1], dtype=float) for _, values in curves if len(values[0])]
    grid = np.unique(np.concatenate(told)) if told else np.zeros(0)
    steps = np.full((len(told), len(grid)), np.nan)
    for row, (seed_told, seed_best) in enumerate(zip(told, best)):
        order = np.argsort(seed_told, kind='stable')
        last = np.searchsorted(seed_told[order], grid, side='right') - 1
        steps[row] = np.where(last >= 0, seed_best[order][np.maximum(last, 0)], np.nan)
    with np.errstate(all='ignore'):
        low, middle, high = (np.nanpercentile(steps, q, axis=0) if len(told) else grid
                             for q in (25, 50, 75))
    return grid, low, middle, high


def plot_convergence(path, panels, title):
    """Best fitness so far against evaluations per configuration (campaign_figures)."""
    campaign_figures.plot_convergence(path, panels, title, seed_band)


def read_campaign(out):
    """Return campaign.json of a campaign folder, or raise UserError."""
    path = pathlib.Path(out) / 'campaign.json'
    try:
        return json.loads(path.read_text(encoding='utf-8'))
    except (OSError, ValueError) as error:
        raise UserError(f'{path}: not a reproduce campaign ({error})') from None


def load_measures(out, experiment, seeds, suffix=''):
    """Return {configuration key: [measures record per seed of `seeds`]} of a campaign folder."""
    measured = {}
    for configuration in experiment.configurations:
        records_of_seeds = []
        for seed in seeds:
            path = pathlib.Path(out) / 'measures' / f'{run_key(configuration, seed)}{suffix}.json'
            if path.exists():
                records_of_seeds.append(json.loads(path.read_text(encoding='utf-8')))
        measured[configuration.key] = records_of_seeds
    return measured


def row_head(experiment, budget, configuration, name, **extra):
    """Return the columns a table row starts with: what was run, under `name`, then `extra`."""
    return {'experiment': experiment.name, 'configuration': name, **extra,
            'preset': configuration.preset, 'policy': configuration.policy,
            'algorithm': configuration.algorithm_name,
            'world_states': training_worlds(configuration, budget), 'budget': budget.name,
            'iterations': budget.iterations, 'population': budget.population,
            'unseen_worlds': budget.unseen_worlds,
            'tolerance': experiment.tolerance.describe(),
            'unit': error_unit(experiment.tolerance)}


def configuration_rows(experiment, budget, measured):
    """Return the table rows (dicts) of an experiment, one per configuration with measures."""
    rows = []
    for configuration in experiment.configurations:
        if not measured[configuration.key]:
            continue
        row = row_head(experiment, budget, configuration, configuration.key)
        row.update(pooled_row(measured[configuration.key], experiment.tolerance))
        row.update(also_columns(measured[configuration.key], experiment.also))
        rows.append(row)
    return rows


def shares_within(measured, tolerance):
    """Return (pooled share, shares by seed) of the runs' unseen worlds within a tolerance."""
    by_seed = [np.asarray(record['worlds']['errors'][tolerance.kind]) < tolerance.limit
               for record in measured]
    return (float(np.mean(np.concatenate(by_seed))),
            tuple(float(np.mean(within)) for within in by_seed))


def also_columns(measured, tolerances):
    """Return {column: value}: the pooled share within each further tolerance, and by seed."""
    columns = {}
    for tolerance in tolerances:
        pooled, by_seed = shares_within(measured, tolerance)
        columns[also_column(tolerance)] = pooled
        columns[also_column(tolerance) + '_by_seed'] = by_seed
    return columns


def also_column(tolerance):
    """Return the table column of the share within a further tolerance, e.g. 'within_x'."""
    return f'within_{tolerance.kind}'


def structure_rows(experiment, budget, measured):
    """Return a row per (configuration, structure): each structure's best over the seeds."""
    rows = []
    for configuration in experiment.configurations:
        structures = {}
        for record in measured[configuration.key]:
            for structure, values in record.items():
                structures.setdefault(structure, []).append(values)
        for structure in sorted(structures, key=lambda text: (text.count(','), text)):
            row = row_head(experiment, budget, configuration,
                           f'{configuration.key} {structure}', structure=structure)
            row.update(pooled_row(structures[structure], experiment.tolerance))
            row.update(also_columns(structures[structure], experiment.also))
            rows.append(row)
    return rows


def write_results(out, experiment, budget, seeds, figure_format='png'):
    """
    Write the tables (.csv, .md) and figures of a campaign folder; return their paths.

    figure_format: 'png', 'svg' or 'pdf', the figures' format (report.md shows each).
    """
    out = pathlib.Path(out)
    measured = load_measures(out, experiment, seeds)
    rows = configuration_rows(experiment, budget, measured)
    name = experiment.name
    paths = [out / f'{name}.csv', out / f'{name}.md', out / f'{name}.{figure_format}']
    write_table(out, name, rows, experiment.also)
    lines = [f'# {name}', '', experiment.summary + '.', '',
             f'Budget {budget.describe()}; {seeds_text(seeds)}; a row per configuration, '
             'the unseen worlds of its seeds pooled.', '',
             markdown_table(rows, experiment.tolerance, also=experiment.also)]
    labels = [f'{row["policy"]} {row["algorithm"]} {row["world_states"]}w' for row in rows]
    if len(set(labels)) < len(labels):  # levers that differ by a task option, not algorithm
        labels = [row['configuration'] for row in rows]
    groups = [(label, measured[row['configuration']]) for label, row in zip(labels, rows)]
    if groups:
        plot_errors(paths[2], groups, experiment.tolerance, f'{name}, {budget.name} budget')
        lines += [f'![{paths[2].name}]({paths[2].name})', '']
    else:
        paths.pop()
    if experiment.per_structure:
        by_structure = load_measures(out, experiment, seeds, '.structures')
        rows = structure_rows(experiment, budget, by_structure)
        write_table(out, f'{name}-structures', rows, experiment.also)
        figure = out / f'{name}-structures.{figure_format}'
        plot_errors(figure, [(row['structure'], [values for record in
                                                 by_structure[row['configuration'].split()[0]]
                                                 for text, values in record.items()
                                                 if text == row['structure']])
                             for row in rows],
                    experiment.tolerance, f"{name}: each structure's best (Fig. 3)",
                    kinds=('position', 'orientation'))
        lines += ["## Each structure's best design (Fig. 3)", '',
                  markdown_table(rows, experiment.tolerance, 'structure', experiment.also),
                  f'![{figure.name}]({figure.name})', '']
        paths += [out / f'{name}-structures.csv', figure]
    panels = convergence_panels(out, experiment, seeds) if experiment.convergence else []
    if panels:
        figure = out / f'{name}-convergence.{figure_format}'
        plot_convergence(figure, panels, f'{name}, {budget.name} budget')
        lines += ['## Convergence', '', f'![{figure.name}]({figure.name})', '']
        paths.append(figure)
    paths[1].write_text('\n'.join(lines), encoding='utf-8')
    return paths
