"""
Rollouts per second of a reproduce campaign's runs, and the time another budget would take.

    python tools/campaign_rates.py results/task5-joint-limits-smoke task5-joint-limits \
        --budget paper [--seeds 5] [--cores 2] [--hosts 4 --host-cores 8]

Reads each finished run's bag (its optimizer's wall time and budget: generations x candidates
x world states), prints per configuration the rollouts per wall second measured here, and
estimates the campaign at `--budget` from those rates: on this machine, and on H hosts of C
cores (the rate scaled by the cores, the runs' fixed costs left out: an estimate, not a
measurement). A smoke campaign's small batches spend a larger share of their time on
start-up and dispatch than long runs do, so its rates make the estimates pessimistic.
"""

import argparse
import pathlib

from hand_codesign.analysis import campaign, records
from hand_codesign.core.experiments import EXPERIMENTS, run_key, training_worlds
from hand_codesign.core.preview import run_budget
from hand_codesign.core.runs import load_run_task


def measured_rate(runs_dir, configuration):
    """Return (rollouts, wall seconds) of the configuration's finished runs."""
    rollouts = seconds = 0.0
    for path in sorted(pathlib.Path(runs_dir).glob(f'{configuration.key}-seed*')):
        if path.name.count('.resume'):
            continue
        key = path.name
        bags = campaign.attempts(runs_dir, key)
        if campaign.finished_bag(runs_dir, key) is None:
            continue
        for bag in bags:
            record = records.open_run(bag, warn=False)
            summary = records.last_summary(record)
            if summary is None:
                continue
            info = record.run_info
            rollouts += float(summary['evaluations']) * info.world_states
            seconds += float(summary['wall_time'])
    return rollouts, seconds


def budget_rollouts(folder, configuration, budget):
    """Return the rollouts one run of the configuration may spend at `budget` (core.preview)."""
    task = load_run_task(pathlib.Path(folder) / 'tasks' / f'{configuration.key}.yaml', 1,
                         budget.iterations, budget.population,
                         training_worlds(configuration, budget))
    return run_budget(task)['rollouts']


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('folder')
    parser.add_argument('experiment', choices=list(EXPERIMENTS))
    parser.add_argument('--budget', default='paper')
    parser.add_argument('--seeds', type=int)
    parser.add_argument('--cores', type=int, default=2, help='cores of this machine')
    parser.add_argument('--hosts', type=int, default=4)
    parser.add_argument('--host-cores', type=int, default=8)
    arguments = parser.parse_args()
    experiment = EXPERIMENTS[arguments.experiment]
    budget = experiment.budget(arguments.budget)
    seeds = arguments.seeds or budget.seeds
    runs_dir = pathlib.Path(arguments.folder) / 'runs'
    total = 0.0
    print(f'{"configuration":24} {"rollouts/s here":>16} {"hours at " + budget.name:>16}')
    for configuration in experiment.configurations:
        rollouts, seconds = measured_rate(runs_dir, configuration)
        if not seconds:
            print(f'{configuration.key:24} {"no finished run":>16}')
            continue
        rate = rollouts / seconds
        needed = budget_rollouts(arguments.folder, configuration, budget) * seeds / rate
        total += needed
        print(f'{configuration.key:24} {rate:16.0f} {needed / 3600:16.2f}')
    hosts = total * arguments.cores / (arguments.hosts * arguments.host_cores)
    print(f'{experiment.name} at {budget.describe()}, {seeds} seeds, example run '
          f'{run_key(experiment.configurations[0], 1)}:')
    print(f'  about {total / 3600:.1f} h on this machine ({arguments.cores} cores), about '
          f'{hosts / 3600:.1f} h on {arguments.hosts} hosts of {arguments.host_cores} cores')


if __name__ == '__main__':
    main()
