"""
Benchmark and validation of cheaper physics settings (a task's `physics` section) on Task 5.

Measures, in one run:
- the designs: --designs candidates spread evenly over a seeded CMA-ES search on Task 5
  (Table I's settings, --generations x --population), those that are simulated (no start
  collision), with their fitness;
- speed: evaluate() with the cheaper settings over a sample of those designs against
  bench_core's bare loop (stepping and torques only, Table I's settings), in interleaved
  rounds, best of 3; and against the same bare loop on the PyPI wheel's PyBullet, in a process
  of its own (bench_pybullet_build's worker): the issue's "today's bare loop", from before
  `make fast-physics` built PyBullet (target >= 1.6: the cheaper physics on top of the build);
- ranking: Spearman's rank correlation of the designs' fitness under both settings (target
  >= 0.98);
- robustness: the best designs on a grid of world states (`grid_world_states`, 3 values per
  quantity) under both settings; the median and 90th percentile of the final position error
  must move by less than 5 %.

Usage: python bench/bench_physics.py [--solver-iterations 5]
       [--contact-breaking-threshold 0.005] [--designs 200] [--generations 50]
       [--population 16] [--world-states 8]
"""

import argparse
import os
import pathlib
import tempfile
import time

from bench_core import bare_loop
from bench_pybullet_build import build_pybullet, measure
from hand_codesign.core.evaluate import evaluate, shared_simulator
from hand_codesign.core.experiments.robustness import evaluate_robustness
from hand_codesign.core.search.factory import make_optimizer
from hand_codesign.core.sim.objectives import goal_schedule
from hand_codesign.core.task import load_task, PhysicsSpec
from hand_codesign.core.task.genome import genome_spec
import numpy as np

TASK_FILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'config', 'tasks',
                         'task5.yaml')


def searched_designs(task, generations, count):
    """
    Return (genomes, fitness) of `count` simulated candidates spread over a CMA-ES run.

    The run lasts `generations`; candidates that start in collision (not simulated, the same
    under any physics) are left out, and `count` of the rest are taken evenly over the run.
    """
    optimizer = make_optimizer(task, genome_spec(task).size)
    genomes, fitness = [], []
    for _ in range(generations):
        batch = optimizer.ask()
        results = {}
        for candidate in batch:
            evaluation = evaluate(candidate.x, task)
            results[candidate.candidate_id] = evaluation.objectives
            if not evaluation.collision:
                genomes.append(np.asarray(candidate.x))
                fitness.append(evaluation.fitness)
        optimizer.tell(results)
    chosen = np.linspace(0, len(genomes) - 1, min(count, len(genomes))).round().astype(int)
    return [genomes[index] for index in chosen], np.array(fitness)[chosen]


def spearman(a, b):
    """Return Spearman's rank correlation of two samples (average ranks for ties)."""
    def ranks(values):
        order = np.argsort(values, kind='stable')
        ranked = np.empty(len(values))
        ranked[order] = np.arange(len(values))
        for value in np.unique(values):
            tied = values == value
            ranked[tied] = ranked[tied].mean()
        return ranked
    return float(np.corrcoef(ranks(np.asarray(a)), ranks(np.asarray(b)))[0, 1])


def speed_ratio(reference, fast, genomes, rounds=3):
    """Return (reference bare-loop rate, fast evaluate() rate) in steps per CPU second."""
    simulator = shared_simulator()
    seconds = np.zeros(2)
    steps = 0
    for x in genomes:
        best = np.full(2, np.inf)
        for _ in range(rounds):
            start = time.process_time()
            result = evaluate(x, fast)
            elapsed = time.process_time() - start
            best = np.minimum(best, (bare_loop(reference, x, simulator, True), elapsed))
        seconds += best
        steps += int(round(result.simulated_time / fast.time_step))
    reference_steps = (len(genomes) * reference.num_world_states
                       * simulator.plan(goal_schedule(reference)).num_steps)
    return reference_steps / seconds[0], steps / seconds[1]


def wheel_bare_rate(genomes, rounds=3):
    """Return the PyPI wheel's bare-loop rate on `genomes` (steps per CPU second), or None."""
    wheel = build_pybullet.wheel_copy()
    if not wheel.exists():
        return None  # the installed PyBullet is the wheel: the reference above is the same
    with tempfile.TemporaryDirectory() as folder:
        genomes_file = pathlib.Path(folder) / 'genomes.npy'
        np.save(genomes_file, np.array(genomes))
        run = measure(wheel.parent, genomes_file, rounds)
    return run['steps']['bare'] / run['bare']


def robustness_change(reference, fast, genomes, fitness, count):
    """Print the final-error percentiles of the best designs under both settings."""
    worst = 0.0
    for index in np.argsort(fitness)[:count]:
        rows = []
        for task in (reference, fast):
            errors = evaluate_robustness(genomes[index], task, values_per_quantity=3)
            rows.append(np.percentile(errors.final_errors[:, 0], [50, 90]))
        change = np.abs(rows[1] - rows[0]) / rows[0]
        worst = max(worst, float(np.max(change)))
        print(f'    design {index:3d}: final position error p50 {rows[0][0] * 1e3:.2f} -> '
              f'{rows[1][0] * 1e3:.2f} mm, p90 {rows[0][1] * 1e3:.2f} -> '
              f'{rows[1][1] * 1e3:.2f} mm (change {np.max(change) * 100:.1f} %)')
    return worst


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--solver-iterations', type=int, default=5)
    parser.add_argument('--contact-breaking-threshold', type=float, default=0.005)
    parser.add_argument('--designs', type=int, default=200)
    parser.add_argument('--generations', type=int, default=50)
    parser.add_argument('--population', type=int, default=16)
    parser.add_argument('--world-states', type=int, default=8)
    parser.add_argument('--speed-sample', type=int, default=16)
    parser.add_argument('--robust-designs', type=int, default=3)
    arguments = parser.parse_args()
    reference = load_task(TASK_FILE).replace(
        num_world_states=arguments.world_states, population=arguments.population, seed=1,
        iterations=10 ** 6)
    fast = reference.replace(physics=PhysicsSpec(
        arguments.solver_iterations, arguments.contact_breaking_threshold))
    genomes, fitness = searched_designs(reference, arguments.generations,
                                        arguments.designs)
    fast_fitness = np.array([evaluate(x, fast).fitness for x in genomes])
    sample = genomes[::max(1, len(genomes) // arguments.speed_sample)][:arguments.speed_sample]
    raw, rate = speed_ratio(reference, fast, sample)
    wheel = wheel_bare_rate(sample)
    print(f'Task 5, physics {fast.physics} against the Table I defaults {reference.physics} '
          f'({time.strftime("%H:%M:%S")})')
    print(f'  {len(genomes)} designs over a CMA-ES run ({arguments.generations} x '
          f'{arguments.population}, {arguments.world_states} worlds), fitness '
          f'{fitness.min():.4f} to '
          f'{fitness.max():.4f}')
    print(f'  bare loop, Table I physics      {raw:9.0f} steps/s')
    print(f'  evaluate(), cheaper physics     {rate:9.0f} steps/s   '
          f'{rate / raw:.3f} of the bare loop')
    if wheel is None:
        print("  (no copy of the PyPI wheel: the bare loop above is the wheel's)")
        wheel = raw
    else:
        print(f'  bare loop, Table I physics, PyPI wheel {wheel:9.0f} steps/s')
    print(f"  speed-up {rate / wheel:.3f} against the wheel's bare loop   (target >= 1.6)")
    print(f'  Spearman rank correlation of the fitness {spearman(fitness, fast_fitness):.4f}'
          '   (target >= 0.98)')
    print('  robustness of the best designs (3^6 = 729 world states):')
    worst = robustness_change(reference, fast, genomes, fitness, arguments.robust_designs)
    print(f'  largest percentile change {worst * 100:.1f} %   (target < 5 %)')


if __name__ == '__main__':
    main()
