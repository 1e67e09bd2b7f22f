"""
A reproduce campaign's folder: its runs' bags, its settings, its cached measures.

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
"""

import json
import pathlib

from hand_codesign.campaign.experiment import run_key
from hand_codesign.errors import UserError

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
