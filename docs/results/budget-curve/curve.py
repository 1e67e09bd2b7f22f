"""
A budget curve: one run's design measured on unseen worlds after each share of its budget.

Each BAG is a run continued from the one before (`hand-codesign run --resume BAG
--iterations N`), so its design is the design a run of N generations ends with. Each is
measured on --unseen worlds (the run seed's unseen stream, as `reproduce` measures) under the
experiment's tolerance, with the project's measures (hand_codesign.campaign.measures), and the
per-world measures are cached beside the table as OUT-BAGNAME.json (a rerun reads them back).
A raced run (`worlds: {racing: ...}`) is a row with the rollouts its race ran, beside the
curve of the unraced runs.

Usage (from the repository's root):
    .venv/bin/python docs/results/budget-curve/curve.py --tolerance plane --limit 0.005 \
        --table-i 100 --out docs/results/budget-curve/task5 BAG ...

Writes OUT.md (generations, rollouts run, the share of Table I's budget, within tolerance,
median and p90 of the error, the run's wall time) and OUT.png (within against rollouts).
"""

import argparse
import json
import pathlib
import sys

from hand_codesign.analysis import records
from hand_codesign.analysis.figures import load_pyplot
from hand_codesign.analysis.resume import runs_continued
from hand_codesign.campaign.measures import measure_bag
from hand_codesign.campaign.measures import world_measures_of
from hand_codesign.campaign.tables import error_unit
from hand_codesign.core.experiments.measures import summarize
from hand_codesign.core.experiments.measures import Tolerance
from hand_codesign.errors import UserError


def rollouts_run(record):
    """Return the rollouts the run ran: every told candidate's worlds (racing counted)."""
    info = record.run_info
    met = records.told_worlds(record)
    if met:
        return records.raced_rollouts(met)[0]
    return info.iterations * info.population * info.world_states


def wall_minutes(bags):
    """
    Return each run's wall time in minutes, with that of the runs it continued added.

    A run counts the runs it continued only where its bag starts after their generations
    (analysis.resume.runs_continued): a resume that started over ran them again itself.
    """
    times = []
    for bag in bags:
        record = records.open_run(bag, warn=False)
        chain = runs_continued(record) + [record]
        times.append(sum(float(records.last_summary(part)['wall_time']) for part in chain) / 60)
    return times


def measured(bag, tolerance, unseen, cache):
    """Return the bag's design measures, read from cache if measured before."""
    if cache.exists():
        return json.loads(cache.read_text())
    values = measure_bag(bag, tolerance, unseen)
    cache.write_text(json.dumps(values))
    return values


def main():
    """Measure each bag, write the table and the figure."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    parser.add_argument('bags', nargs='+', metavar='BAG')
    parser.add_argument('--tolerance', required=True, help='error kind: plane, orientation, pose')
    parser.add_argument('--limit', type=float, required=True, help='m or rad (pose: 1)')
    parser.add_argument('--table-i', type=int, required=True, help="Table I's generations")
    parser.add_argument('--also', nargs='*', default=[], metavar='KIND:LIMIT',
                        help='further shares within, e.g. orientation:0.1 plane:0.005')
    parser.add_argument('--unseen', type=int, default=1000)
    parser.add_argument('--out', required=True, help='table and figure path, without suffix')
    arguments = parser.parse_args()
    out = pathlib.Path(arguments.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tolerance = Tolerance(arguments.tolerance, arguments.limit)
    also = [Tolerance(kind, float(limit)) for kind, limit in
            (text.split(':') for text in arguments.also)]
    lines = ['| run | generations | rollouts run | of Table I | within | '
             f'median ({error_unit(tolerance)}) | p90 | '
             + ''.join(f'{other.describe()} | ' for other in also) + 'wall (min) |',
             '|---|---|---|---|---|---|---|' + '---|' * len(also) + '---|']
    points = []
    for bag, minutes in zip(arguments.bags, wall_minutes(arguments.bags)):
        record = records.open_run(bag, warn=False)
        info = record.run_info
        rollouts = rollouts_run(record)
        whole = arguments.table_i * info.population * info.world_states
        cache = out.parent / f'{out.name}-{pathlib.Path(bag).name}.json'
        values = measured(bag, tolerance, arguments.unseen, cache)
        summary, worlds = values['summary'], world_measures_of(values['worlds'])
        shares = ''.join(f'{summarize(worlds, other).within:.1%} | ' for other in also)
        lines.append(f'| {pathlib.Path(bag).name} | {info.iterations} | {rollouts:,} | '
                     f"{rollouts / whole:.2f} | {summary['within']:.1%} | "
                     f"{summary['median']:.4g} | {summary['p90']:.4g} | {shares}{minutes:.1f} |")
        if not records.told_worlds(record):   # the curve: unraced runs
            points.append((rollouts / whole, summary['within']))
    out.with_suffix('.md').write_text('\n'.join(lines) + '\n')
    pyplot = load_pyplot()
    figure, axes = pyplot.subplots(figsize=(5, 3.2))
    axes.plot(*zip(*points), marker='o')
    axes.set_xscale('log', base=2)
    axes.set_xlabel("rollouts, as a share of Table I's budget")
    axes.set_ylabel('share of the unseen worlds within')
    axes.set_title(tolerance.describe(), fontsize=9)
    figure.tight_layout()
    figure.savefig(out.with_suffix('.png'), dpi=120)
    print('\n'.join(lines))


if __name__ == '__main__':
    try:
        main()
    except UserError as error:  # a bag that is missing or not ours: one line, no traceback
        sys.exit(f'curve.py: {error}')
