"""
Benchmark of the whole node system against the bare stepping loop of the core benchmark.

Measures, in one run on the Task 5 scene:
- the raw single-core stepping rate: bench_core's bare loop (same built worlds, same torques,
  nothing else) over candidates of the task;
- the system's rate with 1 and with 2 evaluators: `hand-codesign run` as separate processes
  (recorder, evaluators, optimizer over DDS), physics steps of every evaluation in the bag over
  the wall time from the first candidate sent to the last evaluation received.
Prints the ratio of the 2-evaluator rate to twice the raw rate (target >= 0.85) and of the
2-evaluator rate to the 1-evaluator rate (target >= 1.8).

Usage: python bench/bench_system.py [--iterations 8] [--popsize 16] [--world-states 16]
"""

import argparse
import os
import pathlib
import subprocess
import sys
import tempfile
import time

from bench_core import bare_loop, candidates
from hand_codesign.analysis.bag import read_run
from hand_codesign.core.evaluate import shared_simulator
from hand_codesign.core.objectives import goal_schedule
from hand_codesign.core.task import load_task
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
TASK_FILE = ROOT / 'config' / 'tasks' / 'task5.yaml'


def raw_rate(task, count):
    """Return steps per second of the bare loop over `count` candidates (best of 3 each)."""
    simulator = shared_simulator()
    steps_per_candidate = task.num_world_states * simulator.plan(goal_schedule(task)).num_steps
    seconds = sum(min(bare_loop(task, x, simulator, True) for _ in range(3))
                  for x in candidates(task, count, seed=5))
    return count * steps_per_candidate / seconds


def system_rate(task, evaluators, arguments, folder):
    """Run the system; return physics steps per wall second of the evaluation phase."""
    bag = pathlib.Path(folder) / f'evaluators-{evaluators}'
    command = [sys.executable, '-m', 'hand_codesign.cli', 'run', '--task', str(TASK_FILE),
               '--evaluators', str(evaluators), '--bag', str(bag), '--quiet',
               '--iterations', str(arguments.iterations), '--popsize', str(arguments.popsize),
               '--world-states', str(arguments.world_states), '--seed', '1']
    subprocess.run(command, check=True, cwd=ROOT, stdout=subprocess.DEVNULL,
                   env=dict(os.environ, AMENT_PREFIX_PATH=os.environ.get(
                       'AMENT_PREFIX_PATH', sys.prefix)))
    record = read_run(bag)
    evaluations = record.evaluations.select(record.evaluations['status'] == 0)
    steps = np.sum(evaluations['simulated_time']) / task.time_step
    started = np.min(record.candidates['log_time'])
    ended = np.max(evaluations['log_time'])
    return steps / ((ended - started) * 1e-9)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--iterations', type=int, default=8)
    parser.add_argument('--popsize', type=int, default=16)
    parser.add_argument('--world-states', type=int, default=16)
    arguments = parser.parse_args()
    task = load_task(TASK_FILE).replace(num_world_states=arguments.world_states, seed=1)
    with tempfile.TemporaryDirectory() as folder:
        raw = raw_rate(task, 6)
        one = system_rate(task, 1, arguments, folder)
        two = system_rate(task, 2, arguments, folder)
        raw_again = raw_rate(task, 6)
    raw = max(raw, raw_again)
    print(f'Task 5, {arguments.iterations} generations x {arguments.popsize} candidates x '
          f'{arguments.world_states} worlds ({time.strftime("%H:%M:%S")})')
    print(f'  raw single-core stepping (bench_core bare loop)  {raw:9.0f} steps/s')
    print(f'  system, 1 evaluator                               {one:9.0f} steps/s')
    print(f'  system, 2 evaluators                              {two:9.0f} steps/s')
    print(f'  2 evaluators / (2 x raw)   {two / (2 * raw):.3f}   (target >= 0.85)')
    print(f'  2 evaluators / 1 evaluator {two / one:.3f}   (target >= 1.8)')


if __name__ == '__main__':
    main()
