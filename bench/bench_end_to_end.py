"""
Benchmark of a whole run as a user sees it, against the code before the performance work.

Runs `hand-codesign run` on Task 5 with 2 evaluators, alternately with this tree and with the
reference: the tree of commit REFERENCE (the code when the performance issue was filed, before
the single-threaded evaluator, the audit and dispatch changes, the start-up work and the
profile-optimized PyBullet), extracted with `git archive` and run with the PyPI wheel's
PyBullet (kept by tools/build_pybullet.py beside the venv). Per run, from its bag
(analysis.records.stepping_rate): the physics steps of the accepted evaluations, each
candidate counted once, over the wall time from the first candidate recorded to the last
evaluation. Prints the ratio of the fastest runs (target >= 1.3) and whether both versions
told the search the same generations (they must: the same best design, bit for bit).

Usage: python bench/bench_end_to_end.py [--iterations 3] [--population 80] [--world-states 64]
                                        [--turns 2] [--reference COMMIT]
"""

import argparse
import os
import pathlib
import subprocess
import sys
import tarfile
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / 'tools'))

import build_pybullet  # noqa: E402, I100: a tool script, not a package
from hand_codesign.analysis.records import stepping_rate  # noqa: E402
from hand_codesign.bag.reader import read_run  # noqa: E402, I100
import numpy as np  # noqa: E402

REFERENCE = 'c411ce1'
TASK = pathlib.Path('config') / 'tasks' / 'task5.yaml'


def extract(commit, folder):
    """Extract the package and configuration of `commit` into `folder`; return it."""
    archive = folder / 'reference.tar'
    with open(archive, 'wb') as stream:
        subprocess.run(['git', 'archive', commit, 'hand_codesign', 'config'], cwd=ROOT,
                       stdout=stream, check=True)
    with tarfile.open(archive) as tar:
        tar.extractall(folder / 'reference', filter='data')
    return folder / 'reference'


def run(tree, module_paths, arguments, bag):
    """Run Task 5 with the package in `tree`; return the bag's end-to-end steps per second."""
    command = [sys.executable, '-m', 'hand_codesign.cli', 'run', '--task', str(tree / TASK),
               '--evaluators', '2', '--bag', str(bag), '--quiet', '--seed', '1',
               '--iterations', str(arguments.iterations),
               # the reference's `run` knows the old name only
               '--population' if tree == ROOT else '--popsize', str(arguments.population),
               '--world-states', str(arguments.world_states)]
    if tree == ROOT:  # a free domain; the reference's `run` picked one without being asked
        command += ['--domain-id', 'auto']
    environment = dict(os.environ, PYTHONPATH=os.pathsep.join(map(str, module_paths)))
    subprocess.run(command, cwd=tree, env=environment, check=True, stdout=subprocess.DEVNULL)
    return stepping_rate(read_run(bag))


def best_fitnesses(bag):
    """Return the best fitness of every generation the run told, as recorded."""
    return np.asarray(read_run(bag).generation_summaries['best_fitness']).tolist()


def listed(rates):
    return ', '.join(f'{rate:.0f}' for rate in rates)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--iterations', type=int, default=3)
    parser.add_argument('--population', type=int, default=80)
    parser.add_argument('--world-states', type=int, default=64)
    parser.add_argument('--turns', type=int, default=2, help='runs of each version, alternated')
    parser.add_argument('--reference', default=REFERENCE, help='commit to compare against')
    arguments = parser.parse_args()
    wheel = build_pybullet.wheel_copy()
    wheel_paths = [wheel.parent] if wheel.exists() else []
    with tempfile.TemporaryDirectory() as name:
        folder = pathlib.Path(name)
        reference = extract(arguments.reference, folder)
        versions = {'reference': (reference, [reference] + wheel_paths), 'current': (ROOT, [])}
        rates = {version: [] for version in versions}
        summaries = {}
        for turn in range(arguments.turns):
            for version, (tree, paths) in versions.items():
                bag = folder / f'{version}-{turn}'
                rates[version].append(run(tree, paths, arguments, bag))
                summaries.setdefault(version, best_fitnesses(bag))
    best = {version: max(values) for version, values in rates.items()}
    print(f'Task 5, {arguments.iterations} generations x {arguments.population} candidates x '
          f'{arguments.world_states} worlds, 2 evaluators, seed 1; fastest of {arguments.turns} '
          f'alternate runs ({time.strftime("%H:%M:%S")}, load average '
          f'{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)')
    pybullet = 'the wheel' if wheel_paths else 'the installed one (no wheel copy found)'
    print(f'  reference {arguments.reference} (PyBullet: {pybullet})   '
          f'{best["reference"]:9.0f} steps/s   ({listed(rates["reference"])})')
    print(f'  this tree                                 {best["current"]:9.0f} steps/s   '
          f'({listed(rates["current"])})')
    print(f'  end to end, this tree / reference   {best["current"] / best["reference"]:.3f}   '
          '(target >= 1.3)')
    same = summaries['reference'] == summaries['current']
    print(f'  the same best fitness in every generation: {"yes" if same else "NO"}')


if __name__ == '__main__':
    main()
