"""
What an experiment is: Configurations, Budgets and a Tolerance; seeds; a configuration's task.

An Experiment is a list of Configurations (a pinned preset, an algorithm and a number of
world states), a Tolerance that says when a world counts as a success, and Budgets (`smoke`,
`reduced`, `paper`: generations x candidates per configuration, the unseen worlds every final
design is measured on, and the default number of seeds). A campaign runs every configuration
once per seed, each as a normal `hand-codesign run`. The experiments themselves are modules of
`hand_codesign.campaign.experiments`, each registered by name.

Pinned presets: the task files live, as the paper ran them, in `config/reproduce/` (copies of
`config/tasks/` frozen when the experiments were defined), and every option a run depends on
(algorithm, seed, generations, population, world states) is passed explicitly; a campaign
copies the task text it runs into its own folder and resumes from that copy. So later changes
to the presets in `config/tasks/` do not change what `reproduce` reproduces.

Budgets: `paper` is Table I's; `reduced` fits this 2-core machine in about an hour per
experiment (Tasks 5 and 6) to a few hours (Tasks 1 and 4); `smoke` takes minutes.
"""

import dataclasses
import pathlib
import re
import sys
from typing import Dict, Tuple

from hand_codesign.core.experiments.measures import Tolerance
import yaml

ALGORITHM_NAMES = {'cma': 'CMA-ES', 'mocma': 'MO-CMA-ES', 'ipop-cma': 'IPOP-CMA-ES',
                   'bipop-cma': 'BIPOP-CMA-ES', 'cma-mae': 'CMA-MAE', 'cma-me': 'CMA-ME'}
BUDGET_NAMES = ('smoke', 'reduced', 'paper')


@dataclasses.dataclass(frozen=True)
class Configuration:
    """One line of an experiment's table: a pinned preset run with one algorithm."""

    key: str  # file-safe name, unique in the experiment
    preset: str  # file name in config/reproduce/
    algorithm: str  # cma | mocma | ipop-cma | bipop-cma | cma-mae | cma-me
    world_states: int  # training worlds per candidate (unless the budget sets them)
    policy: str  # torque | pd (for the table)
    options: Tuple[Tuple[str, object], ...] = ()  # (dotted task key, value) set in the preset

    @property
    def algorithm_name(self):
        """Return the algorithm as the paper names it (CMA-ES, MO-CMA-ES)."""
        return ALGORITHM_NAMES[self.algorithm]


@dataclasses.dataclass(frozen=True)
class Budget:
    """Generations and candidates per run, unseen worlds per design, default seeds."""

    name: str
    iterations: int
    population: int
    unseen_worlds: int
    seeds: int
    world_states: int = 0  # training worlds of every configuration; 0: each configuration's

    def describe(self):
        """Return e.g. 'smoke: 4 generations x 8 candidates, 100 unseen worlds'."""
        return (f'{self.name}: {self.iterations} generations x {self.population} candidates '
                f'per run, measured on {self.unseen_worlds} unseen worlds')


@dataclasses.dataclass(frozen=True)
class Experiment:
    """A named set of configurations, their tolerance, budgets and what to draw."""

    name: str
    summary: str
    configurations: Tuple[Configuration, ...]
    tolerance: Tolerance
    budgets: Dict[str, Budget]
    per_structure: bool = False  # hierarchy: measure each structure's best (Fig. 3)
    convergence: bool = False  # draw the configurations' convergence side by side
    beyond_paper: bool = False  # ours, not the paper's: listed, but not part of `all`
    also: Tuple[Tolerance, ...] = ()  # further errors the tables give the share within

    def tolerances(self):
        """Return the tolerance and the further ones, each measured on every design."""
        return (self.tolerance,) + self.also

    def budget(self, name):
        """Return the Budget called name, or raise KeyError."""
        return self.budgets[name]


def budgets(smoke, reduced, paper):
    """
    Return {name: Budget} of the three budgets, each given as a tuple.

    Args:
        smoke, reduced, paper: (iterations, population, unseen worlds, seeds), each a Budget's
            fields after its name.

    Returns:
        dict of 'smoke', 'reduced' and 'paper' to Budget, in that order.
    """
    return {name: Budget(name, *values)
            for name, values in zip(BUDGET_NAMES, (smoke, reduced, paper))}


def pinned_dir():
    """Return the folder of the pinned presets (source tree, else the installed share)."""
    source = pathlib.Path(__file__).resolve().parents[2] / 'config' / 'reproduce'
    if source.is_dir():
        return source
    return pathlib.Path(sys.prefix) / 'share' / 'hand_codesign' / 'config' / 'reproduce'


_ALGORITHM_LINE = re.compile(r'^(\s+algorithm:\s*)([\w-]+)', re.MULTILINE)


def configuration_task_text(configuration, preset_text):
    """
    Return the pinned preset text with the configuration's algorithm and options set.

    Without options the preset's text is kept, comments and all; options (a configuration
    beyond the paper) are set in the parsed task, which is written back without comments.
    """
    text, count = _ALGORITHM_LINE.subn(
        lambda match: match.group(1) + configuration.algorithm, preset_text, count=1)
    if count != 1:
        raise ValueError(f'{configuration.preset}: no "optimizer.algorithm" line to pin')
    if not configuration.options:
        return text
    task = yaml.safe_load(text)
    for dotted, value in configuration.options:
        *sections, key = dotted.split('.')
        mapping = task
        for section in sections:
            mapping = mapping.setdefault(section, {})
        mapping[key] = value
    changes = ', '.join(f'{dotted}: {value}' for dotted, value in configuration.options)
    return (f'# config/reproduce/{configuration.preset} (see its comments) with {changes}\n'
            + yaml.safe_dump(task, sort_keys=False))


MOST_SEEDS_COUNTED = 20
"""A bare N above this is refused: '--seeds 105' is likelier meant as seed 105 than as 105 runs."""


def parse_seeds(text):
    """
    Return the seeds a `--seeds` value names, in order, each once.

    'N' is seeds 1 to N (the tuning seeds 1-3 are '3'; N at most MOST_SEEDS_COUNTED), 'A-B' the
    range A to B ('101-105', the fresh seeds of the headline figures), 'A,B,...' a list.
    Raises ValueError with what was expected otherwise.
    """
    text = str(text).strip()
    expected = f'--seeds: expected N (seeds 1 to N), A-B or A,B,...; got {text!r}'
    if re.fullmatch(r'\d+', text):
        count = int(text)
        if count > MOST_SEEDS_COUNTED:
            raise ValueError(f'--seeds: {count} alone means seeds 1 to {count}, {count} runs of '
                             f'every configuration; write {count}-{count} for seed {count} only, '
                             f'or 1-{count} for all of them')
        seeds = tuple(range(1, count + 1))
    elif re.fullmatch(r'\d+-\d+', text):
        first, last = (int(part) for part in text.split('-'))
        if last < first:
            raise ValueError(f'{expected} (a range runs upwards: {last}-{first})')
        seeds = tuple(range(first, last + 1))
    else:
        try:
            seeds = tuple(int(part) for part in text.split(','))
        except ValueError:
            raise ValueError(expected) from None
    if not seeds or min(seeds) < 1:
        raise ValueError(expected + ' (seeds are 1 or more)')
    return tuple(dict.fromkeys(seeds))


def seeds_text(seeds):
    """Return seeds as the tables name them: 'seeds 1 to 3', 'seeds 101 to 105', 'seed 4'."""
    seeds = tuple(seeds)
    if len(seeds) == 1:
        return f'seed {seeds[0]}'
    if seeds == tuple(range(seeds[0], seeds[0] + len(seeds))):
        return f'seeds {seeds[0]} to {seeds[-1]}'
    return 'seeds ' + ', '.join(str(seed) for seed in seeds)


def training_worlds(configuration, budget):
    """Return the worlds per candidate of a configuration's runs at a budget."""
    return budget.world_states or configuration.world_states


def run_key(configuration, seed):
    """Return the name of a run of a campaign, e.g. 'torque-cma-8w-seed1'."""
    return f'{configuration.key}-seed{seed}'


__all__ = ['ALGORITHM_NAMES', 'Budget', 'budgets', 'Configuration', 'Experiment',
           'parse_seeds', 'pinned_dir', 'run_key', 'seeds_text', 'training_worlds']
