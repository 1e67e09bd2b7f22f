"""
Benchmark: how many rollouts racing over the worlds would save, and what it would get wrong.

Runs a short CMA-ES search of each task (Table I's population, --generations generations,
--world-states worlds, seed --seed) without racing, every candidate on every world, and replays
each generation's race (core.search.racing) on the per-world objectives it recorded, for each
stated --ranges R (a world's weighted objectives taken to lie in a band R wide):

  saved     the share of the generation's rollouts (worlds of candidates not starting in
            collision) the stopped candidates would not have run
  wrong     stopped candidates that are among the mu best on all the worlds (the race's
            bound failed for them), per generation
  beyond R  the share of the worlds whose weighted objectives lie outside [0, R]: the bound's
            statement is false for them (unstable worlds, knocked-away objects)

and the spread of the per-world weighted objectives (median, 90th, 99th percentile), to choose
R. The race replayed on an unraced search is not the raced search itself (its later generations
would differ); the lead's raced runs on tuning seeds measure that (docs: the issue's commands).

Usage: python bench/bench_racing.py [--tasks task5 task6] [--generations 5] [--world-states 64]
       [--ranges 0.02 0.05 0.1] [--rounds 4] [--delta 0.05] [--engine mujoco] [--seed 1]
"""

import argparse
import dataclasses
import os
import time

from hand_codesign.core.evaluate import evaluate, torque_penalty_of
from hand_codesign.core.search.factory import make_optimizer
from hand_codesign.core.search.racing import Race, RoundAnswer
from hand_codesign.core.sim.objectives import combine_worlds
from hand_codesign.core.task import load_task, RacingSpec
from hand_codesign.core.task.genome import genome_spec
import numpy as np

TASKS = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'config', 'tasks')


def generations(task, count):
    """Yield (candidates, evaluations) of `count` generations of an unraced CMA-ES search."""
    optimizer = make_optimizer(task, genome_spec(task).size)
    for _ in range(count):
        batch = optimizer.ask()
        results = [evaluate(candidate.x, task) for candidate in batch]
        optimizer.tell({c.candidate_id: r.objectives for c, r in zip(batch, results)})
        yield batch, results


def replay(task, batch, results, spec, selected):
    """Return (rollouts saved, rollouts, wrong stops) of the race of one recorded generation."""
    penalties = {c.candidate_id: torque_penalty_of(c.x, task) for c in batch}
    values = {c.candidate_id: r for c, r in zip(batch, results)}
    race = Race([c.candidate_id for c in batch], task.num_world_states, selected, spec,
                task.objective_weights, penalties)
    while not race.done:
        first, end = race.share
        race.told({i: RoundAnswer(combine_worlds(values[i].world_objectives[first:end]),
                                  values[i].world_objectives[first:end], values[i].collision)
                   for i in race.racing})
    fitness = np.array([r.fitness for r in results])
    best = {batch[index].candidate_id for index in np.argsort(fitness, kind='stable')[:selected]}
    rollouts = sum(task.num_world_states for r in results if not r.collision)
    return race.rollouts_saved(), rollouts, len(best & race.stopped)


def spans(recorded, weights):
    """
    Return (raw, centred) spans of the simulated candidates' worlds' weighted objectives.

    A span is max - min over a candidate's worlds; centred values are less the generation's
    median on each world (what its candidates share there).
    """
    raw, centred = [], []
    for _, results in recorded:
        values = np.array([r.world_objectives @ weights for r in results if not r.collision])
        if not len(values):
            continue
        shifted = values - np.median(values, axis=0)
        raw += np.ptp(values, axis=1).tolist()
        centred += np.ptp(shifted, axis=1).tolist()
    return np.array(raw), np.array(centred)


def bench(name, arguments):
    """Print the figures of one task."""
    task = load_task(os.path.join(TASKS, name + '.yaml')).replace(
        num_world_states=arguments.world_states, seed=arguments.seed, iterations=10 ** 6)
    task = task.replace(physics=dataclasses.replace(task.physics, engine=arguments.engine))
    selected = make_optimizer(task.replace(worlds=dataclasses.replace(
        task.worlds, racing=RacingSpec())), genome_spec(task).size).selected
    started = time.perf_counter()
    recorded = list(generations(task, arguments.generations))
    weights = np.asarray(task.objective_weights)
    raw, centred = spans(recorded, weights)
    print(f'{name}: {arguments.generations} generations x {task.population} on '
          f'{task.num_world_states} worlds ({arguments.engine}, seed {arguments.seed}, mu '
          f'{selected}; {time.perf_counter() - started:.0f} s)')
    for label, span in (('raw', raw), ("centred on each world's median", centred)):
        print(f"  span of a candidate's worlds' weighted objectives, {label}: median "
              f'{np.median(span):.4f}, 90th percentile {np.percentile(span, 90):.4f}, 99th '
              f'{np.percentile(span, 99):.4f}')
    for value_range in arguments.ranges:
        spec = RacingSpec(arguments.rounds, value_range, arguments.delta)
        counts = np.array([replay(task, batch, results, spec, selected)
                           for batch, results in recorded])
        beyond = np.mean(centred > value_range)
        print(f'  range {value_range:g}: saved {counts[:, 0].sum() / counts[:, 1].sum():.1%} '
              f'of the rollouts (per generation: '
              f'{", ".join(f"{s / max(n, 1):.0%}" for s, n, _ in counts)}); wrong stops per '
              f'generation {counts[:, 2].mean():.2f}; candidates spanning more than R '
              f'{beyond:.1%}')


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--tasks', nargs='+', default=['task5', 'task6'])
    parser.add_argument('--generations', type=int, default=5)
    parser.add_argument('--world-states', type=int, default=64)
    parser.add_argument('--ranges', nargs='+', type=float, default=[0.02, 0.05, 0.1])
    parser.add_argument('--rounds', type=int, default=4)
    parser.add_argument('--delta', type=float, default=0.05)
    parser.add_argument('--engine', default='mujoco', choices=['pybullet', 'mujoco'])
    parser.add_argument('--seed', type=int, default=1)
    arguments = parser.parse_args()
    for name in arguments.tasks:
        bench(name, arguments)


if __name__ == '__main__':
    main()
