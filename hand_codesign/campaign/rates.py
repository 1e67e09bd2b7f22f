"""
Physics steps per second of a reproduce campaign's runs, and the time another budget would take.

    hand-codesign reproduce task5-joint-limits --out results/task5-joint-limits-reduced \
        --rates paper [--seeds 5] [--cores 2] [--hosts 4 --host-cores 8]

Reads each finished run's bag (its optimizer's wall time and the steps its evaluations
simulated), prints per configuration the physics steps per wall second measured here, and
estimates the campaign at the budget after `--rates` from those rates and the steps that budget
allows (core.run.preview.run_budget, full rollouts: pessimistic where early termination cuts
them): on this machine, and on H hosts of C cores (the rate scaled by the cores, the runs'
fixed costs left out: an estimate, not a measurement). A smoke campaign's small batches spend
a larger share of their time on start-up and dispatch than long runs do, so its rates make the
estimates pessimistic.
"""

import dataclasses
import pathlib
from typing import List

from hand_codesign.analysis import records
from hand_codesign.campaign.experiment import Experiment
from hand_codesign.campaign.experiment import run_key
from hand_codesign.campaign.experiment import training_worlds
from hand_codesign.campaign.folders import attempts
from hand_codesign.campaign.folders import finished_bag
from hand_codesign.core.run.preview import run_budget
from hand_codesign.core.run.runs import load_run_task
from hand_codesign.core.task import TaskError
from hand_codesign.errors import UserError
import numpy as np


@dataclasses.dataclass(frozen=True)
class Machines:
    """Where the estimate is for: this machine's cores, and H hosts of C cores."""

    cores: int = 2
    hosts: int = 4
    host_cores: int = 8


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
        if finished_bag(runs_dir, key) is None:
            continue
        for bag in attempts(runs_dir, key):
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
    # the campaign's pinned task is its record, as a bag's task is: an old key reads silently
    return load_run_task(task_file, 1, budget.iterations, budget.population,
                         training_worlds(configuration, budget), warn_old_names=False)


def rate_lines(folder: str, experiment: Experiment, budget_name: str, seeds: int,
               machines: Machines = Machines()) -> List[str]:
    """
    Return the rates table of a campaign folder and its estimate at another budget.

    Args:
        folder: the campaign folder (its runs/ and tasks/).
        experiment: the experiment the campaign ran.
        budget_name: the budget to estimate ('smoke', 'reduced' or 'paper').
        seeds: how many seeds of every configuration the estimate counts.
        machines: the cores of this machine and of the hosts the estimate is for.

    Returns:
        lines of text: per configuration its physics steps per wall second here and the hours
        its runs would take at the budget; then the whole campaign's hours.

    Raises:
        UserError: an unknown budget, a folder that is no campaign, a run without its bag.
    """
    if budget_name not in experiment.budgets:
        raise UserError(f'--rates: {experiment.name} has no budget "{budget_name}"; expected '
                        f'one of {", ".join(experiment.budgets)}')
    budget = experiment.budget(budget_name)
    runs_dir, tasks_dir = pathlib.Path(folder) / 'runs', pathlib.Path(folder) / 'tasks'
    if not (runs_dir.is_dir() and tasks_dir.is_dir()):
        raise UserError(f'{folder}: not a campaign folder (expected runs/ and tasks/ in it, '
                        f'written by `hand-codesign reproduce {experiment.name}`)')
    total = 0.0
    width = max(len(configuration.key) for configuration in experiment.configurations)
    lines = [f'{"configuration":{width}} {"steps/s here":>16} {"hours at " + budget.name:>16}']
    for configuration in experiment.configurations:
        task_file = tasks_dir / f'{configuration.key}.yaml'
        if not task_file.exists():
            continue  # a campaign of some configurations (`reproduce --only`)
        try:
            task = budget_task(task_file, configuration, budget)
        except TaskError as error:
            raise UserError(str(error)) from None
        steps, seconds = measured_rate(runs_dir, configuration, task.time_step)
        if not seconds:
            lines.append(f'{configuration.key:{width}} {"no finished run":>16}')
            continue
        rate = steps / seconds
        needed = run_budget(task)['physics_steps'] * seeds / rate
        total += needed
        lines.append(f'{configuration.key:{width}} {rate:16.0f} {needed / 3600:16.2f}')
    hosts = total * machines.cores / (machines.hosts * machines.host_cores)
    return lines + [
        f'{experiment.name} at {budget.describe()}, {seeds} seeds, example run '
        f'{run_key(experiment.configurations[0], 1)}:',
        f'  about {total / 3600:.1f} h on this machine ({machines.cores} cores), about '
        f'{hosts / 3600:.1f} h on {machines.hosts} hosts of {machines.host_cores} cores']
