"""
The cost of physics as a randomized quantity (issue 47): a candidate in both engines.

Evaluates the same candidates (the genome's centre and --designs - 1 seeded draws near it, so
that they rarely start in collision) on the same worlds with `physics.engine: pybullet` and with
`physics.engines: [pybullet, mujoco]`, in interleaved rounds, and prints the CPU seconds of this
process (best of --rounds) and their ratio; issue 47 asks at most 1.6 for the whole run.

Usage: python bench/bench_two_engines.py [--task config/tasks/task5.yaml] [--world-states 16]
       [--designs 6] [--rounds 3]
"""

import argparse
import time

from hand_codesign.core.evaluate import evaluate
from hand_codesign.core.task import load_task
from hand_codesign.core.task.genome import genome_spec
import numpy as np


def seconds(task, genomes):
    """Return the CPU seconds of this process evaluating every genome on task."""
    started = time.process_time()
    for x in genomes:
        evaluate(x, task)
    return time.process_time() - started


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--task', default='config/tasks/task5.yaml')
    parser.add_argument('--world-states', type=int, default=16)
    parser.add_argument('--designs', type=int, default=6)
    parser.add_argument('--rounds', type=int, default=3)
    arguments = parser.parse_args()
    task = load_task(arguments.task).replace(num_world_states=arguments.world_states)
    size = genome_spec(task).size
    draws = np.random.default_rng(1).normal(0.5, 0.05, (arguments.designs - 1, size))
    genomes = [np.full(size, 0.5), *np.clip(draws, 0, 1)]
    tasks = {name: task.replace(physics=task.physics.with_engines(engines))
             for name, engines in (('pybullet', ('pybullet',)),
                                   ('pybullet+mujoco', ('pybullet', 'mujoco')),
                                   ('mujoco', ('mujoco',)))}
    for name, each in tasks.items():  # warm up: imports, first builds
        seconds(each, genomes[:1])
    best = {name: min(seconds(each, genomes) for _ in range(arguments.rounds))
            for name, each in tasks.items()}
    for name, value in best.items():
        print(f'{name}: {value:.3f} CPU s for {len(genomes)} candidates x '
              f'{arguments.world_states} worlds ({value / len(genomes) * 1000:.0f} ms each)')
    print(f"ratio pybullet+mujoco / pybullet: {best['pybullet+mujoco'] / best['pybullet']:.2f}")


if __name__ == '__main__':
    main()
