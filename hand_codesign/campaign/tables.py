"""
An experiment's tables: a row per configuration (or per structure), pooled over its seeds.

Measures (core.experiments.measures): each run's final design (the optimizer's choice, the final
GenerationSummary's `best_x`) on the budget's unseen worlds of the run's seed. Per
configuration over its seeds: the unseen worlds of all seeds pooled: the share within the
tolerance, the median and 90th percentile of the error; **joint limits found**: the share of
seeds whose design found them (core.experiments.measures: it ends within the tolerance resting on a
limit it reached, touching the box, in at least half of its successes and a quarter of its worlds);
beside it, the mean share of the worlds that are such limit successes, and the looser
earlier measure (resting on a limit while touching, whatever the outcome).
"""

import pathlib

from hand_codesign.analysis.tables import error_text
from hand_codesign.analysis.tables import percent
from hand_codesign.analysis.tables import write_csv
from hand_codesign.campaign.experiment import training_worlds
from hand_codesign.core.experiments.measures import DesignMeasures
import numpy as np


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
