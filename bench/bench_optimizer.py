"""
Benchmark of the optimizers' own time against the evaluation time of a generation.

For a population of 150 and the task's genome size, measures the optimizer's time per
generation (ask + tell, no evaluation) of CMA-ES and MO-CMA-ES, and as the reference, measured
in the same run, the evaluation time of that generation on 128 world states: a few real
evaluations with core.evaluate, extrapolated to the population on one core. Prints the ratio
(target: below 1 %).

The optimizers are told synthetic objective vectors. For MO-CMA-ES they are two objectives in
pure trade-off, (t, 1 - t) of the first gene, so that parents and offspring all lie on one
Pareto front: the costliest case of its hypervolume selection (150 of 300 points removed one by
one). Times are this process's CPU time.

    python bench/bench_optimizer.py [--task config/tasks/task5.yaml] [--population 150]
        [--world-states 128] [--generations 30] [--evaluations 3]
"""

import argparse
import pathlib
import sys
import time

from hand_codesign.core import genome_spec, load_task, TaskError
from hand_codesign.core.evaluate import evaluate
from hand_codesign.core.search.optimizers import CmaEs, MoCmaEs
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]


def synthetic_objectives(x, count):
    """Return `count` objectives; the first two in pure trade-off, the others a sphere."""
    trade_off = np.abs(np.mod(x[0], 2.0) - 1.0)  # in [0, 1], a triangle wave like the genome's
    sphere = float(np.sum((x - 0.5) ** 2))
    values = [trade_off, 1.0 - trade_off] if count > 1 else [sphere]
    return np.array(values + [sphere] * (count - len(values)))


def optimizer_seconds(optimizer, generations, num_objectives):
    """Return CPU seconds of ask + tell for each generation."""
    seconds = []
    for _ in range(generations):
        start = time.process_time()
        candidates = optimizer.ask()
        ask_done = time.process_time()
        results = {c.candidate_id: synthetic_objectives(c.x, num_objectives)
                   for c in candidates}
        tell_start = time.process_time()
        optimizer.tell(results)
        seconds.append(ask_done - start + time.process_time() - tell_start)
    return np.array(seconds)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--task', default=str(ROOT / 'config' / 'tasks' / 'task5.yaml'))
    parser.add_argument('--population', type=int, default=150)
    parser.add_argument('--world-states', type=int, default=128)
    parser.add_argument('--generations', type=int, default=30)
    parser.add_argument('--evaluations', type=int, default=3)
    args = parser.parse_args(argv)
    try:
        task = load_task(args.task).replace(num_world_states=args.world_states)
    except TaskError as error:
        print(f'error: {error}', file=sys.stderr)
        return 2
    spec = genome_spec(task)
    weights = task.objective_weights

    rng = np.random.default_rng(0)
    points = [spec.initial_mean() + 0.1 * rng.standard_normal(spec.size)
              for _ in range(args.evaluations)]
    evaluate(points[0], task.replace(num_world_states=1))  # warm up: simulator, caches
    start = time.process_time()
    for x in points:
        evaluate(x, task)
    per_candidate = (time.process_time() - start) / args.evaluations
    generation_seconds = per_candidate * args.population

    print(f'task {task.name}: genome {spec.size} values, population {args.population}, '
          f'{args.world_states} world states')
    print(f'reference: evaluation {per_candidate:.3f} s per candidate ({args.evaluations} '
          f'measured), {generation_seconds:.1f} s per generation on one core')
    setups = [('CMA-ES', CmaEs, len(weights), weights),
              ('MO-CMA-ES', MoCmaEs, 2, [1.0, 0.1])]
    for name, algorithm, num_objectives, setup_weights in setups:
        optimizer = algorithm(spec.size, setup_weights, args.population,
                              args.generations + 1, seed=0)
        seconds = optimizer_seconds(optimizer, args.generations, num_objectives)
        front = optimizer.result.pareto_ids
        print(f'{name:9s} ({num_objectives} objective{"s" if num_objectives > 1 else ""}): '
              f'ask+tell mean {1e3 * seconds.mean():.1f} ms, max {1e3 * seconds.max():.1f} ms '
              f'per generation' + (f', Pareto front {len(front)}' if front else '') +
              f'; ratio to evaluation: mean {100 * seconds.mean() / generation_seconds:.3f} %, '
              f'max {100 * seconds.max() / generation_seconds:.3f} % (target < 1 %)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
