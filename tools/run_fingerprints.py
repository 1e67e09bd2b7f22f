"""
Fingerprint four tiny real runs, so a refactor can show its results are bit-identical.

Runs, each with a fixed seed through the project's own ``hand-codesign run`` (real processes,
real physics, a real bag):

- ``task5``: Task 5 (config/tasks/task5.yaml), CMA-ES;
- ``task4-hierarchy``: Task 4's hierarchy with MO-CMA-ES (config/tasks/task4.yaml), its check
  on 4 worlds instead of 128 and hands of at most two fingers, to stay small;
- ``task1-two-stage``: Task 1's two stages (config/tasks/task1.yaml);
- ``task5-cma-mae``: Task 5 searched by quality diversity (``optimizer.algorithm: cma-mae``).

Each prints one SHA-256 over the run's ``result.json`` and every GenerationSummary read back
from its bag (``hand_codesign.bag.reader.read_topics``), in recorded order. Left out, because
they differ from one run of the same seed to the next: the run id (drawn fresh for each run)
and everything holding it (the bag path, the signing key's public half), wall-clock stamps
(``wall_time``, the bag's ``log_time`` and ``publish_time``, ``started``/``finished``/
``seconds`` of result.json), signatures, host and process names. Every objective value,
genome, id and count is kept, floats exactly (their shortest round-trip text).

Usage: python tools/run_fingerprints.py [--only NAME ...] [--keep DIR]
"""

import argparse
import hashlib
import json
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile

from hand_codesign.bag.reader import read_topics
import numpy as np
import yaml

ROOT = pathlib.Path(__file__).resolve().parents[1]
SUMMARY_TYPE = 'hand_codesign_msgs/msg/GenerationSummary'
# name -> (task file, changes to its YAML, extra flags of `run`)
RUNS = {
    'task5': ('config/tasks/task5.yaml', {},
              ['--seed', '3', '--iterations', '3', '--population', '4', '--world-states', '2']),
    'task4-hierarchy': ('config/tasks/task4.yaml',
                        {'hierarchy.evaluation_world_states': 4, 'hierarchy.max_fingers': 2},
                        ['--seed', '5', '--iterations', '2', '--population', '4',
                         '--world-states', '2']),
    'task1-two-stage': ('config/tasks/task1.yaml', {},
                        ['--seed', '7', '--iterations', '2', '--population', '4',
                         '--world-states', '2']),
    'task5-cma-mae': ('config/tasks/task5.yaml', {'optimizer.algorithm': 'cma-mae'},
                      ['--seed', '11', '--iterations', '3', '--population', '6',
                       '--world-states', '2']),
}
# keys left out wherever they appear (see the module's docstring for why)
VOLATILE = {'run_id', 'wall_time', 'signature', 'log_time', 'publish_time', 'started',
            'finished', 'seconds', 'wall_seconds', 'host', 'hostname', 'pid', 'bag',
            'summary_key', 'date', 'time', 'duration_s', 'elapsed'}
# fields added after the runs were first fingerprinted, left out where empty (a run without the
# lever they record), so that the fingerprints of runs without it stay comparable across them
LATER_FIELDS = {'told_worlds'}   # racing (core.search.racing)


def empty(value):
    """Return whether a value read back is empty: no items, or only the table's NaN padding."""
    items = value if isinstance(value, list) else [value]
    return all(isinstance(item, float) and item != item for item in items)


def task_file(name, folder):
    """Write the task of one run (its preset with the run's changes) and return its path."""
    preset, changes, _ = RUNS[name]
    if not changes:
        return ROOT / preset
    spec = yaml.safe_load((ROOT / preset).read_text())
    for dotted, value in changes.items():
        *parents, key = dotted.split('.')
        place = spec
        for parent in parents:
            place = place.setdefault(parent, {})
        place[key] = value
    path = folder / f'{name}.yaml'
    path.write_text(yaml.safe_dump(spec, sort_keys=False))
    return path


def plain(value):
    """Return value as JSON-ready lists, numbers and strings, volatile keys left out."""
    if isinstance(value, dict):
        return {key: plain(item) for key, item in sorted(value.items())
                if key not in VOLATILE}
    if isinstance(value, np.ndarray):
        return plain(value.tolist())
    if isinstance(value, (list, tuple)):
        return [plain(item) for item in value]
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, bytes):
        return value.hex()
    return value


def fingerprint(bag):
    """Return the SHA-256 over a finished run's result.json and generation summaries."""
    result = json.loads((bag / 'result.json').read_text())
    tables, warnings = read_topics(bag, [SUMMARY_TYPE])
    summaries = tables[SUMMARY_TYPE]
    rows = [{key: item for key, item in plain(summaries.row(index)).items()
             if not (key in LATER_FIELDS and empty(item))} for index in range(len(summaries))]
    text = json.dumps({'result': plain(result), 'summaries': rows, 'warnings': len(warnings)},
                      sort_keys=True, allow_nan=True)
    return hashlib.sha256(text.encode()).hexdigest(), len(rows)


def run(name, folder):
    """Run one of RUNS into folder and return its fingerprint line."""
    command = shutil.which('hand-codesign') or str(pathlib.Path(sys.executable).parent
                                                   / 'hand-codesign')
    bag = folder / name
    task = task_file(name, folder)
    subprocess.run([command, 'run', '--task', str(task), '--evaluators', '2', '--bag',
                    str(bag), '--domain-id', 'auto', '--quiet', *RUNS[name][2]],
                   check=True, cwd=ROOT, env=dict(os.environ), stdout=subprocess.DEVNULL)
    digest, count = fingerprint(bag)
    return f'{name} {digest} ({count} summaries)'


def main():
    """Run the chosen runs and print one fingerprint a line."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--only', nargs='+', choices=sorted(RUNS), default=list(RUNS))
    parser.add_argument('--keep', help='folder to keep the bags in (default: a temporary one)')
    args = parser.parse_args()
    if args.keep:
        folder = pathlib.Path(args.keep)
        folder.mkdir(parents=True, exist_ok=True)
        for name in args.only:
            print(run(name, folder), flush=True)
        return
    with tempfile.TemporaryDirectory(prefix='fingerprints-') as folder:
        for name in args.only:
            print(run(name, pathlib.Path(folder)), flush=True)


if __name__ == '__main__':
    main()
