"""
The final Pareto front of a finished MO-CMA-ES run, its designs measured on unseen worlds.

MO-CMA-ES (Table I's Task 4) ends on a front of designs that trade one objective against the
other, and the run returns one of them: by the paper's rule (III.C, `optimizer.front_choice:
normalized`) the one closest to zero with each objective min-max normalized over the front;
with `front_choice: weighted` the one with the least weighted sum of the task's weights. The
search is the same either way, so one run answers for both: this script rebuilds the run's
search from its bag (as `run --resume` does), takes its final front, measures every design of
it on --screen unseen worlds and the designs both rules pick (and the best of the screen) on
--unseen worlds, with the project's measures (the run seed's unseen stream, as `reproduce`
and curve.py measure).

Usage (from the repository's root):
    .venv/bin/python docs/results/budget-curve/front.py BAG --tolerance pose --limit 1 \
        --also orientation:0.1 plane:0.005 --out docs/results/budget-curve/task4-front-BAG

Writes OUT.md: the picks on the --unseen worlds, then every front design on the screen.
"""

import argparse
import pathlib
import sys

from hand_codesign.analysis import records
from hand_codesign.analysis.resume import recorded_run
from hand_codesign.core.experiments.measures import measure_worlds
from hand_codesign.core.experiments.measures import summarize
from hand_codesign.core.experiments.measures import Tolerance
from hand_codesign.core.experiments.measures import unseen_world_states
from hand_codesign.core.search.optimizers import front_index
from hand_codesign.core.search.optimizers import replay
from hand_codesign.core.search.search import Search
from hand_codesign.errors import UserError
import numpy as np


def final_front(bag):
    """Return (task, objective names, ids, genomes, objectives) of the run's final front."""
    record = records.open_run(bag, warn=False)
    task = records.run_task_of(record)
    search = Search(task)
    replay(search, *recorded_run(record))   # the runs it continued too
    result = search.optimizer.result
    return (task, records.objective_names_of(record), list(result.pareto_ids),
            np.asarray(result.pareto_x), np.asarray(result.pareto_objectives))


def shares(measures, tolerances):
    """Return the share within each tolerance and the median of the first one's error."""
    summaries = [summarize(measures, tolerance) for tolerance in tolerances]
    return [summary.within for summary in summaries], summaries[0].median


def row(label, within, median):
    """Return a table row of shares within and the median."""
    return f'| {label} | ' + ' | '.join(f'{share:.1%}' for share in within) + f' | {median:.3g} |'


def main():
    """Measure the run's final front and both rules' picks, write the table."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    parser.add_argument('bag')
    parser.add_argument('--tolerance', required=True, help='error kind: plane, orientation, pose')
    parser.add_argument('--limit', type=float, required=True, help='m or rad (pose: 1)')
    parser.add_argument('--also', nargs='*', default=[], metavar='KIND:LIMIT')
    parser.add_argument('--screen', type=int, default=200)
    parser.add_argument('--unseen', type=int, default=1000)
    parser.add_argument('--out', required=True, help='table path, without suffix')
    arguments = parser.parse_args()
    tolerances = [Tolerance(arguments.tolerance, arguments.limit)] + [
        Tolerance(kind, float(limit)) for kind, limit in
        (text.split(':') for text in arguments.also)]
    task, names, ids, genomes, objectives = final_front(arguments.bag)
    weights = np.asarray(task.objective_weights)
    header = ' | '.join(tolerance.describe() for tolerance in tolerances)
    screen = unseen_world_states(task, arguments.screen)
    screened, first_share = [], []
    for index, candidate_id in enumerate(ids):
        within, median = shares(measure_worlds(genomes[index], task, screen), tolerances)
        first_share.append(within[0])
        screened.append(row(f'{candidate_id} | ' + ' | '.join(
            f'{value:.4g}' for value in objectives[index])
            + f' | {objectives[index] @ weights:.4g}', within, median))
        print(screened[-1], flush=True)
    picks = {'normalized (III.C)': front_index(objectives, weights, 'normalized'),
             'weighted': front_index(objectives, weights, 'weighted'),
             f'best of the screen on {arguments.screen} worlds': int(np.argmax(first_share))}
    worlds = unseen_world_states(task, arguments.unseen)
    name = pathlib.Path(arguments.bag).name
    lines = [f'{name}: {len(ids)} designs on the final front; the picks on {arguments.unseen} '
             'unseen worlds:', '', f'| pick | candidate | {header} | median |',
             '|---' * (3 + len(tolerances)) + '|']
    for label, index in picks.items():
        within, median = shares(measure_worlds(genomes[index], task, worlds), tolerances)
        lines.append(row(f'{label} | {ids[index]}', within, median))
        print(lines[-1], flush=True)
    lines += ['', f'Every design of the front on {arguments.screen} unseen worlds:', '',
              f'| candidate | {" | ".join(names)} | weighted sum | {header} | median |',
              '|---' * (3 + len(objectives[0]) + len(tolerances)) + '|', *screened]
    pathlib.Path(arguments.out).with_suffix('.md').write_text('\n'.join(lines) + '\n')


if __name__ == '__main__':
    try:
        main()
    except UserError as error:  # a bag that is missing or not ours: one line, no traceback
        sys.exit(f'front.py: {error}')
