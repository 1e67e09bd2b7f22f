"""
Benchmark of a run's start: from `hand-codesign run` to the first candidate sent.

Starts a tiny Task 5 run (1 generation of 4 candidates on 1 world) with 2 evaluators several
times and reads from each bag when the recorder received the first candidate; the time counts
from just before the command is launched (so it includes the interpreter's start, the imports
of every process, DDS discovery and the optimizer's wait for its evaluators). Prints each
start, the median and the best (target: < 3 s), with the load average: on a busy machine the
processes' imports wait for a core.

Usage: python bench/bench_startup.py [--repeats 5]
"""

import argparse
import os
import pathlib
import subprocess
import sys
import tempfile
import time

from hand_codesign.analysis.bag import read_run
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
TASK_FILE = ROOT / 'config' / 'tasks' / 'task5.yaml'


def time_to_first_candidate(folder, index):
    """Run a tiny co-design; return seconds from launch to the first candidate recorded."""
    bag = pathlib.Path(folder) / f'start-{index}'
    command = [sys.executable, '-m', 'hand_codesign.cli', 'run', '--task', str(TASK_FILE),
               '--evaluators', '2', '--bag', str(bag), '--quiet', '--iterations', '1',
               '--popsize', '4', '--world-states', '1', '--seed', '1']
    environment = dict(os.environ, AMENT_PREFIX_PATH=os.environ.get('AMENT_PREFIX_PATH',
                                                                    sys.prefix))
    launched = time.time()
    subprocess.run(command, check=True, cwd=ROOT, stdout=subprocess.DEVNULL, env=environment)
    first = np.min(read_run(bag).candidates['log_time']) * 1e-9
    return first - launched


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--repeats', type=int, default=5)
    arguments = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        times = [time_to_first_candidate(folder, index) for index in range(arguments.repeats)]
    print(f'hand-codesign run to the first candidate sent, {arguments.repeats} starts '
          f'({time.strftime("%H:%M:%S")}, load average {os.getloadavg()[0]:.1f} on '
          f'{os.cpu_count()} cores)')
    print('  each     ' + '  '.join(f'{value:.2f}' for value in times) + ' s')
    print(f'  median   {np.median(times):.2f} s   best {min(times):.2f} s   (target < 3 s)')


if __name__ == '__main__':
    main()
