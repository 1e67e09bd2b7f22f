"""
Physics steps per second of a reproduce campaign's runs, and the time another budget would take.

    python tools/campaign_rates.py results/task5-joint-limits-reduced task5-joint-limits \
        --budget paper [--seeds 5] [--cores 2] [--hosts 4 --host-cores 8]

Reads each finished run's bag (its optimizer's wall time and the steps its evaluations
simulated), prints per configuration the physics steps per wall second measured here, and
estimates the campaign at `--budget` from those rates and the steps that budget allows
(core.run.preview.run_budget, full rollouts: pessimistic where early termination cuts them): on
this machine, and on H hosts of C cores (the rate scaled by the cores, the runs' fixed costs
left out: an estimate, not a measurement). A smoke campaign's small batches spend a larger
share of their time on start-up and dispatch than long runs do, so its rates make the
estimates pessimistic.
"""

import argparse
import pathlib
import sys

from hand_codesign.analysis import campaign, records
from hand_codesign.core.experiments.catalog import EXPERIMENTS, run_key, training_worlds
from hand_codesign.core.run.preview import run_budget
from hand_codesign.core.run.runs import load_run_task
from hand_codesign.core.task import TaskError
from hand_codesign.errors import UserError
import numpy as np


def measured_rate(runs_dir, configuration, time_step):
    """
    Return (physics steps, wall seconds) of the configuration's finished runs.

    Steps are the simulated time of each candidate's accepted evaluation (once per candidate,
    as `simulated_time` counts the steps actually simulated) over the time step, so a stage
    on the nominal world or a rollout cut short counts for what it cost.
    """
    steps = seconds = 0.0
    for path in sorted(pathlib.Path(runs_dir).glob(f'{configuration.key}-seed*')):
        if path.name.count('.resume'):
            continue
        key = path.name
        if campaign.finished_bag(runs_dir, key) is None:
            continue
        for bag in campaign.attempts(runs_dir, key):
            record = records.open_run(bag, warn=False)
            summary = records.last_summary(record)
            if summary is None:
                continue
            _, first = np.unique(record.evaluations['candidate_id'], return_index=True)
            steps += float(np.sum(record.evaluations['simulated_time'][first])) / time_step
            seconds += float(summary['wall_time'])
    return steps, seconds


def budget_task(task_file, configuration, budget):
    """Return the task of one run of the configuration at `budget`, from its campaign file."""
    return load_run_task(task_file, 1, budget.iterations, budget.population,
                         training_worlds(configuration, budget))


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
    if arguments.budget not in experiment.budgets:
        parser.error(f'--budget: {experiment.name} has no budget "{arguments.budget}"; '
                     f'expected one of {", ".join(experiment.budgets)}')
    budget = experiment.budget(arguments.budget)
    seeds = arguments.seeds or budget.seeds
    runs_dir = pathlib.Path(arguments.folder) / 'runs'
    tasks_dir = pathlib.Path(arguments.folder) / 'tasks'
    if not (runs_dir.is_dir() and tasks_dir.is_dir()):
        sys.exit(f'campaign_rates: {arguments.folder}: not a campaign folder (expected runs/ and '
                 f'tasks/ in it, written by `hand-codesign reproduce {experiment.name}`)')
    total = 0.0
    width = max(len(configuration.key) for configuration in experiment.configurations)
    print(f'{"configuration":{width}} {"steps/s here":>16} {"hours at " + budget.name:>16}')
    for configuration in experiment.configurations:
        task_file = tasks_dir / f'{configuration.key}.yaml'
        if not task_file.exists():
            continue  # a campaign of some configurations (`reproduce --only`)
        task = budget_task(task_file, configuration, budget)
        steps, seconds = measured_rate(runs_dir, configuration, task.time_step)
        if not seconds:
            print(f'{configuration.key:{width}} {"no finished run":>16}')
            continue
        rate = steps / seconds
        needed = run_budget(task)['physics_steps'] * seeds / rate
        total += needed
        print(f'{configuration.key:{width}} {rate:16.0f} {needed / 3600:16.2f}')
    hosts = total * arguments.cores / (arguments.hosts * arguments.host_cores)
    print(f'{experiment.name} at {budget.describe()}, {seeds} seeds, example run '
          f'{run_key(experiment.configurations[0], 1)}:')
    print(f'  about {total / 3600:.1f} h on this machine ({arguments.cores} cores), about '
          f'{hosts / 3600:.1f} h on {arguments.hosts} hosts of {arguments.host_cores} cores')


if __name__ == '__main__':
    try:
        main()
    except (TaskError, UserError) as error:  # not a campaign folder, or a run without its bag
        sys.exit(f'campaign_rates: {error}')
