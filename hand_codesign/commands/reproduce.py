"""
`hand-codesign reproduce EXPERIMENT [--budget B] [--seeds S] [--evaluators E] [--out DIR]`.

Runs one of the paper's experiments (hand_codesign.campaign.experiments; `reproduce --list`
names them) as a campaign: every configuration once per seed (`--seeds 3`: 1 to 3, the tuning
seeds; `--seeds 101-105`: fresh seeds for headline figures; or a list `4,7`), each a normal
`hand-codesign run` with its own bag under DIR/runs/, then measures every final design on
worlds it never trained on (core.experiments.measures) and writes the experiment's tables (`.csv`,
`.md`, a row per configuration) and figures into DIR (layout: hand_codesign.campaign.folders).
`--only` runs some of the experiment's configurations: a new lever beside a campaign that
already measured the others.

Interrupted (Ctrl-C, SIGTERM, a reboot), the same command continues: finished runs are kept,
the interrupted run is resumed from its bag (`hand-codesign run --resume`, into a new bag
beside it), measures already computed are reused. Progress covers the whole campaign: run k
of n and the time left, estimated from the runs finished in this session, per physics step of
the budget.
"""

import json
import pathlib
import shlex
import signal
import subprocess
import sys
import time

from hand_codesign.campaign import experiments
from hand_codesign.campaign import folders
from hand_codesign.campaign import measures
from hand_codesign.campaign import results
from hand_codesign.campaign.bands import band_lines
from hand_codesign.campaign.experiment import configuration_task_text
from hand_codesign.campaign.experiment import parse_seeds
from hand_codesign.campaign.experiment import pinned_dir
from hand_codesign.campaign.experiment import run_key
from hand_codesign.campaign.experiment import seeds_text
from hand_codesign.campaign.experiment import training_worlds
from hand_codesign.campaign.rates import Machines
from hand_codesign.campaign.rates import rate_lines
from hand_codesign.commands.run import termination_as_interrupt
from hand_codesign.core.run import preview
from hand_codesign.core.run.runs import load_run_task
from hand_codesign.core.run.summary import format_duration
from hand_codesign.core.search.hierarchy import GROWN_FROM
from hand_codesign.core.task import TaskError
from hand_codesign.errors import UserError
import numpy as np

INTERRUPTED = 130
RESUME_REFUSED = 2  # `run --resume` exit code of a bag it cannot resume (UserError)
STOP_WAIT = 120.0  # s a run may take to close its bag after an interruption
PROGRESS_EVERY = 300.0  # s between a run's progress lines: an hour's run says where it is


def reproduce_command(arguments):
    """Run (or continue) an experiment's campaign and write its tables; return exit code."""
    if arguments.list:
        for name in experiments.experiment_names():
            summary = ('every experiment of the paper above, one after the other'
                       if name == experiments.ALL else experiments.EXPERIMENTS[name].summary)
            print(f'{name}  {summary}')
        return 0
    if getattr(arguments, 'bands', None) or getattr(arguments, 'rates', None):
        return read_back_command(arguments)
    chosen = chosen_experiments(arguments.experiment)
    seeds = check_arguments(arguments)
    out = campaign_folder(arguments)
    campaigns = [Campaign(experiment, arguments.budget, seeds,
                          out if len(chosen) == 1 else out / experiment.name,
                          chosen_configurations(experiment, arguments.only),
                          figure_format=getattr(arguments, 'format', 'png'))
                 for experiment in chosen]
    for item in campaigns:
        item.prepare()
        print(f'reproduce: {item.experiment.name}, budget {item.budget.describe()}; '
              f'{seeds_text(item.seeds)}; {_count(len(item.runs), "run")} of '
              f'{_count(arguments.evaluators, "evaluator")}; '
              f'folder {item.out}', flush=True)
    progress = Progress(sum(len(item.runs) for item in campaigns))
    for item in campaigns:
        progress.pending += item.pending_costs()
    try:
        with termination_as_interrupt():
            for item in campaigns:
                item.run_all(progress, arguments.evaluators)
                item.write_results()
    except KeyboardInterrupt:
        print('reproduce: interrupted; run the same command again to continue (finished runs '
              'are kept, the interrupted one resumes from its bag)', file=sys.stderr)
        return INTERRUPTED
    return 0


def read_back_command(arguments):
    """
    Print what a campaign folder holds, without running: `--bands` or `--rates`.

    --bands: the share within per band of a quantity of the unseen worlds (campaign.bands);
    --rates: the physics steps per second of its runs and the time of another budget
    (campaign.rates). Both read one experiment's folder (--out, default as a campaign's).
    """
    chosen = chosen_experiments(arguments.experiment)
    if len(chosen) != 1:
        raise UserError("--bands and --rates read one experiment's campaign; name it")
    experiment, out = chosen[0], campaign_folder(arguments)
    seeds = check_arguments(arguments)
    if arguments.bands:
        edges = arguments.bands
        if len(edges) < 2 or list(edges) != sorted(edges):
            raise UserError(f'--bands: expected two or more edges, ascending; got {edges}')
        seeds = seeds or range(1, experiment.budget(arguments.budget).seeds + 1)
        lines = band_lines(out, experiment, seeds, arguments.quantity, edges)
    else:
        target = experiment.budgets.get(arguments.rates)   # rate_lines refuses a wrong one
        count = len(seeds) if seeds else target.seeds if target else 0
        lines = rate_lines(out, experiment, arguments.rates, count,
                           Machines(arguments.cores, arguments.hosts, arguments.host_cores))
    print('\n'.join(lines))
    return 0


def campaign_folder(arguments):
    """Return the campaign folder: --out, or results/EXPERIMENT-BUDGET."""
    return pathlib.Path(arguments.out or f'results/{arguments.experiment}-{arguments.budget}')


def _count(number, noun):
    """Return `number noun`, the noun plural unless the number is one ("1 run", "2 runs")."""
    return f'{number} {noun}' if number == 1 else f'{number} {noun}s'


def chosen_experiments(name):
    """Return the Experiments of a name (all of them for `all`), or raise UserError."""
    if name is None:
        raise UserError('name an experiment (see `hand-codesign reproduce --list`)')
    if name == experiments.ALL:
        return experiments.paper_experiments()
    if name not in experiments.EXPERIMENTS:
        raise UserError(f'unknown experiment "{name}"; expected one of '
                        f'{", ".join(experiments.experiment_names())}')
    return [experiments.EXPERIMENTS[name]]


def chosen_configurations(experiment, keys):
    """Return the configurations of an experiment named by keys (None: all); or UserError."""
    if keys is None:
        return experiment.configurations
    known = {configuration.key: configuration for configuration in experiment.configurations}
    unknown = [key for key in keys if key not in known]
    if unknown:
        raise UserError(f'--only: {experiment.name} has no configuration '
                        f'{", ".join(unknown)}; expected some of {", ".join(known)}')
    return [known[key] for key in dict.fromkeys(keys)]


def check_arguments(arguments):
    """Return the seeds of --seeds (None: the budget's); raise UserError for a bad value."""
    if arguments.evaluators < 1:
        raise UserError(f'--evaluators: expected 1 or more, got {arguments.evaluators}')
    if arguments.seeds is None:
        return None
    try:
        return parse_seeds(arguments.seeds)
    except ValueError as error:
        raise UserError(str(error)) from None


FIT_SPREAD = 2.0
"""Runs of costs this far apart fit a fixed part; closer costs would make the fit swing wildly."""


class Progress:
    """
    Run k of n of the whole campaign and the time left, from this session's runs.

    A run costs a fixed part (starting processes, measuring) and a part per physics step of its
    budget: both are fitted to the runs done in this session (least squares), so the estimate
    holds for campaigns of tiny runs and of long ones.
    """

    def __init__(self, total):
        self.total = total
        self.number = 0
        self.done_runs = []  # (physics steps, seconds) of the runs done in this session
        self.pending = []  # physics steps of each run not done yet

    def announce(self, key, state):
        """Print the line of the next run."""
        self.number += 1
        seconds = self.seconds_left()
        left = ('time left known after the first run' if seconds is None
                else f'about {format_duration(seconds)} left')
        print(f'reproduce: run {self.number} of {self.total}: {key} ({state}); {left}',
              flush=True)

    def seconds_left(self):
        """Return the estimated seconds of the pending runs, or None before any run ended."""
        if not self.pending:
            return 0.0
        if not self.done_runs:
            return None
        steps, seconds = (np.array(column, dtype=float) for column in zip(*self.done_runs))
        if steps.max() >= FIT_SPREAD * steps.min():
            per_step, fixed = np.polyfit(steps, seconds, 1)
            per_step, fixed = max(per_step, 0.0), max(fixed, 0.0)
        else:
            per_step, fixed = float(np.sum(seconds) / max(np.sum(steps), 1.0)), 0.0
        return sum(fixed + per_step * cost for cost in self.pending)

    def done(self, steps, seconds, whole=True):
        """
        Count a run finished in this session.

        Only a run simulated here from its start (`whole`) tells the cost of a run: one that
        was only measured, or resumed near its end, would make the rest look nearly free.
        """
        if whole:
            self.done_runs.append((steps, seconds))
        self.pending.remove(steps)


class Campaign:
    """One experiment's campaign in its folder: its runs, measures and tables."""

    def __init__(self, experiment, budget_name, seeds, out, configurations=None,
                 figure_format='png'):
        self.experiment = experiment
        self.figure_format = figure_format   # of the figures: png, svg or pdf
        self.budget = experiment.budget(budget_name)
        self.seeds = tuple(seeds or range(1, self.budget.seeds + 1))
        self.out = pathlib.Path(out)
        self.runs_dir = self.out / 'runs'
        self.runs = [(configuration, seed)
                     for configuration in configurations or experiment.configurations
                     for seed in self.seeds]

    # ---------------------------------------------------------------- setup

    def prepare(self):
        """Create or check the campaign folder; pin the task texts; check they load."""
        path = self.out / 'campaign.json'
        settings = {'experiment': self.experiment.name, 'budget': self.budget.name,
                    'iterations': self.budget.iterations,
                    'population': self.budget.population,
                    'unseen_worlds': self.budget.unseen_worlds}
        if path.exists():
            recorded = folders.read_campaign(self.out)
            differs = [key for key, value in settings.items() if recorded.get(key) != value]
            if differs:
                raise UserError(
                    f'--out {self.out}: holds a campaign of {recorded.get("experiment")} at '
                    f'budget {recorded.get("budget")} ({", ".join(differs)} differ); choose '
                    'another --out')
        try:
            (self.out / 'tasks').mkdir(parents=True, exist_ok=True)
        except OSError as error:
            raise UserError(f'--out {self.out}: cannot create the folder: {error}') from None
        path.write_text(json.dumps(dict(settings, seeds=list(self.seeds)), indent=2) + '\n',
                        encoding='utf-8')
        for configuration in self.experiment.configurations:
            task_file = self.task_file(configuration)
            if not task_file.exists():
                preset = pinned_dir() / configuration.preset
                try:
                    text = preset.read_text(encoding='utf-8')
                except OSError as error:
                    raise UserError(f'{preset}: cannot read the pinned preset: {error}')
                task_file.write_text(configuration_task_text(configuration, text),
                                     encoding='utf-8')
            try:
                self.run_task(configuration, self.seeds[0])
            except TaskError as error:
                raise UserError(str(error))

    def task_file(self, configuration):
        return self.out / 'tasks' / f'{configuration.key}.yaml'

    def run_task(self, configuration, seed):
        """Return the Task of one run (the campaign's task text and the budget)."""
        return load_run_task(self.task_file(configuration), seed, self.budget.iterations,
                             self.budget.population,
                             training_worlds(configuration, self.budget))

    def cost(self, configuration):
        """
        Return the physics steps one run of a configuration costs at this budget (estimate).

        The run's budget (every structure of a hierarchy, each optimized REPEATS times, and
        its checks) and its designs' measure on the unseen worlds; early termination and
        pycma's own stops make a run cheaper, never dearer.
        """
        task = self.run_task(configuration, self.seeds[0])
        plan = preview.run_budget(task)
        return (plan['physics_steps']
                + self.budget.unseen_worlds * self.measured_designs(plan)
                * preview.rollout_steps(task))

    def measured_designs(self, plan):
        """Return how many designs of a run are measured: its best, and each structure's."""
        if not self.experiment.per_structure:
            return 1
        searched = [entry for entry in plan['structures'] if not entry.get('grown')]
        return 1 + len(searched) + min(GROWN_FROM, len(plan['structures']) - len(searched))

    # ---------------------------------------------------------------- runs

    def pending_costs(self):
        """Return the physics steps of each run not finished and measured yet."""
        return [self.cost(configuration) for configuration, seed in self.runs
                if not self.measured(configuration, seed)]

    def run_all(self, progress, evaluators):
        """Run, resume or skip every run of the campaign, and measure each."""
        for configuration, seed in self.runs:
            key = run_key(configuration, seed)
            if self.measured(configuration, seed):
                progress.announce(key, 'finished and measured: kept')
                continue
            started = time.monotonic()
            bag = folders.finished_bag(self.runs_dir, key)
            state = ('finished: measuring' if bag else 'resuming from its bag'
                     if folders.attempts(self.runs_dir, key) else 'starting')
            progress.announce(key, state)
            if bag is None:
                bag = self.run_one(configuration, seed, evaluators)
            self.measure(configuration, seed, bag, max(1, evaluators))
            progress.done(self.cost(configuration), time.monotonic() - started,
                          whole=state == 'starting')

    def run_one(self, configuration, seed, evaluators):
        """Run (or resume) one run to its end; return its finished bag."""
        key = run_key(configuration, seed)
        self.runs_dir.mkdir(parents=True, exist_ok=True)
        previous = folders.attempts(self.runs_dir, key)
        bag = folders.next_attempt(self.runs_dir, key)
        common = ['--bag', str(bag), '--evaluators', str(evaluators), '--quiet',
                  '--progress-every', f'{PROGRESS_EVERY:g}',
                  '--domain-id', 'auto']   # campaigns side by side never share a domain
        if previous:
            code = self.call(['--resume', str(previous[-1])] + common)
            if code != RESUME_REFUSED:
                return self.checked(key, bag, code)
            print(f'reproduce: {previous[-1]} cannot be resumed (see above): starting the run '
                  'afresh', flush=True)
        task = self.run_task(configuration, seed)
        code = self.call(['--task', str(self.task_file(configuration)), '--seed', str(seed),
                          '--iterations', str(task.iterations), '--population',
                          str(task.population), '--world-states', str(task.num_world_states)]
                         + common)
        return self.checked(key, bag, code)

    def checked(self, key, bag, code):
        """Return the bag of a run that ended with exit code `code`, or stop the campaign."""
        if code == INTERRUPTED:
            raise KeyboardInterrupt
        if code != 0 or not (bag / 'result.json').exists():
            raise UserError(f'run {key} failed (exit code {code}); its bag and logs: {bag}')
        return bag

    @staticmethod
    def call(run_arguments):
        """Run `hand-codesign run ...` as a child process; on an interruption stop it too."""
        command = [sys.executable, '-m', 'hand_codesign.cli', 'run'] + run_arguments
        print('reproduce: hand-codesign run ' + shlex.join(run_arguments), flush=True)
        # its own process group: a Ctrl-C reaches it once, forwarded below, so that the
        # run is not interrupted again while it closes its bag. Forwarded as SIGTERM, which
        # `run` treats as Ctrl-C: a campaign started in the background (`nohup ... &`) and
        # its children ignore SIGINT, and a run killed after STOP_WAIT leaves its nodes behind
        child = subprocess.Popen(command, process_group=0)
        try:
            return child.wait()
        except KeyboardInterrupt:
            if child.poll() is None:
                child.send_signal(signal.SIGTERM)
            try:
                child.wait(timeout=STOP_WAIT)
            except subprocess.TimeoutExpired:
                child.kill()
                child.wait()
            raise

    # ---------------------------------------------------------------- measures

    def measures_path(self, configuration, seed, suffix=''):
        return self.out / 'measures' / f'{run_key(configuration, seed)}{suffix}.json'

    def measured(self, configuration, seed):
        """Return True if the run is finished and every measure of it is cached."""
        if folders.read_measures(self.measures_path(configuration, seed),
                                 self.error_kinds()) is None:
            return False
        return (not self.experiment.per_structure
                or self.measures_path(configuration, seed, '.structures').exists())

    def error_kinds(self):
        return [tolerance.kind for tolerance in self.experiment.tolerances()]

    def measure(self, configuration, seed, bag, processes):
        """Measure a finished run's design (and each structure's best) on unseen worlds."""
        tolerance, count = self.experiment.tolerance, self.budget.unseen_worlds
        folders.cached_measures(self.measures_path(configuration, seed),
                                lambda: measures.measure_bag(bag, tolerance, count, processes),
                                self.error_kinds())
        if self.experiment.per_structure:
            bags = folders.attempts(self.runs_dir, run_key(configuration, seed))
            folders.cached_measures(
                self.measures_path(configuration, seed, '.structures'),
                lambda: measures.measure_structures(bags, tolerance, count, processes))

    # ---------------------------------------------------------------- results

    def write_results(self):
        """Write the experiment's tables and figures from its runs' measures."""
        paths = results.write_results(self.out, self.experiment, self.budget, self.seeds,
                                      self.figure_format)
        print(f'reproduce: {self.experiment.name} ({self.budget.describe()}, '
              f'{seeds_text(self.seeds)}): '
              f'{", ".join(str(path) for path in paths)}', flush=True)
