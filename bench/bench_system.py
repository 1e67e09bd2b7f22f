"""
Benchmark of the whole node system against the bare stepping loop of the core benchmark.

Measures, in one run on the Task 5 scene:
- the raw single-core stepping rate: bench_core's bare loop (same built worlds, same torques,
  nothing else) over a sample of the very candidates the system evaluated (later generations
  touch the box more and step slower than the first ones, so the sample must be theirs);
- the system's rate with 1 and with 2 evaluators: `hand-codesign run` as separate processes
  (recorder, evaluators, optimizer over DDS), physics steps of the evaluations told to the
  search over the wall time from the first candidate sent to the last evaluation received.
  Audit evaluations (a second evaluator checking an answer, hand_codesign.core.run.audits) are
  cost, not progress: their steps are not counted, their time is. The run's own evaluators
  are audited once each (their first answer); `--audit-fraction 0` leaves even that out.
Prints the ratio of the 2-evaluator rate to twice the raw rate (target >= 0.95 at Table I's
generation size, >= 0.90 at 16 candidates x 8 worlds) and of the 2-evaluator rate to the
1-evaluator rate (target >= 1.8). The rates are wall-clock rates: other processes on the
machine lower them (see the load average printed).

Twice the raw rate is more than two cores give: two bare loops stepping at the same time, in
two processes and nothing else, each step slower than one alone (the cores share caches and
memory). So the benchmark also runs the bare loop in two processes at once over the same
candidates and prints the system's rate against their summed rate: the ceiling of two
processes on this machine, which no change to the system can pass.

The defaults are Table I's Task 5 generation (population 80, 64 world states). Small
generations cost more: every candidate pays a fixed cost besides stepping (building the hand,
each world's object, the objectives: about a tenth of the bare loop's time), and at the end
of each generation one evaluator waits for the other's last candidate.

Usage: python bench/bench_system.py [--iterations 2] [--population 80] [--world-states 64]
                                    [--audit-fraction F]
"""

import argparse
import concurrent.futures
import multiprocessing
import os
import pathlib
import subprocess
import sys
import tempfile
import time

from bench_core import bare_loop
from hand_codesign.analysis.records import evaluation_rows
from hand_codesign.analysis.records import stepping_rate
from hand_codesign.bag.reader import read_run
from hand_codesign.core.evaluate import shared_simulator
from hand_codesign.core.sim.objectives import goal_schedule
from hand_codesign.core.task import load_task
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
TASK_FILE = ROOT / 'config' / 'tasks' / 'task5.yaml'


def raw_rate(task, bag, count):
    """Return steps per second of the bare loop over `count` of the bag's simulated candidates."""
    record = read_run(bag)
    evaluations = record.evaluations.select((record.evaluations['status'] == 0)
                                            & (record.evaluations['simulated_time'] > 0))
    genomes = dict(zip(record.candidates['candidate_id'], record.candidates['genome']))
    chosen = np.random.default_rng(0).choice(evaluations['candidate_id'], count, replace=False)
    simulator = shared_simulator()
    steps_per_candidate = task.num_world_states * simulator.plan(goal_schedule(task)).num_steps
    seconds = sum(min(bare_loop(task, np.asarray(genomes[i]), simulator, True)
                      for _ in range(3)) for i in chosen)
    return count * steps_per_candidate / seconds


def raw_rates_at_once(task, bag, count, processes=2):
    """Return the steps per second of `processes` bare loops run at the same time, summed."""
    spawn = multiprocessing.get_context('spawn')
    with concurrent.futures.ProcessPoolExecutor(processes, mp_context=spawn) as pool:
        return sum(pool.map(raw_rate, [task] * processes, [bag] * processes,
                            [count] * processes))


def system_rate(evaluators, arguments, folder):
    """Run the system; return its bag, physics steps per wall second and audit evaluations."""
    bag = pathlib.Path(folder) / f'evaluators-{evaluators}'
    command = [sys.executable, '-m', 'hand_codesign.cli', 'run', '--task', str(TASK_FILE),
               '--evaluators', str(evaluators), '--bag', str(bag), '--quiet',
               '--iterations', str(arguments.iterations),
               '--population', str(arguments.population),
               '--world-states', str(arguments.world_states), '--seed', '1',
               '--domain-id', 'auto']
    if arguments.audit_fraction is not None:
        command += ['--audit-fraction', str(arguments.audit_fraction)]
    subprocess.run(command, check=True, cwd=ROOT, stdout=subprocess.DEVNULL,
                   env=dict(os.environ, AMENT_PREFIX_PATH=os.environ.get(
                       'AMENT_PREFIX_PATH', sys.prefix)))
    record = read_run(bag)
    audits = int(np.sum(evaluation_rows(record).status == 'duplicate'))
    return bag, stepping_rate(record), audits


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--iterations', type=int, default=2)
    parser.add_argument('--population', type=int, default=80)
    parser.add_argument('--world-states', type=int, default=64)
    parser.add_argument('--audit-fraction', type=float, help="default: hand-codesign run's")
    arguments = parser.parse_args()
    task = load_task(TASK_FILE).replace(num_world_states=arguments.world_states, seed=1)
    with tempfile.TemporaryDirectory() as folder:
        _, one, _ = system_rate(1, arguments, folder)
        bag, two, audits = system_rate(2, arguments, folder)
        raw = raw_rate(task, bag, 24)
        raw_two = raw_rates_at_once(task, bag, 24)
    print(f'Task 5, {arguments.iterations} generations x {arguments.population} candidates x '
          f'{arguments.world_states} worlds ({time.strftime("%H:%M:%S")}, load average '
          f'{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)')
    print(f'  raw single-core stepping (bench_core bare loop)  {raw:9.0f} steps/s')
    print(f'  raw, two processes at once (summed)              {raw_two:9.0f} steps/s')
    print(f'  system, 1 evaluator                               {one:9.0f} steps/s')
    print(f'  system, 2 evaluators                              {two:9.0f} steps/s '
          f'({audits} audit evaluations not counted)')
    target = 0.95 if arguments.population * arguments.world_states >= 80 * 64 else 0.90
    print(f'  2 evaluators / (2 x raw)   {two / (2 * raw):.3f}   (target >= {target:.2f})')
    print(f'  2 evaluators / (2 raw at once) {two / raw_two:.3f}   (ceiling of two processes: 1)')
    print(f'  2 evaluators / 1 evaluator {two / one:.3f}   (target >= 1.8)')


if __name__ == '__main__':
    main()
