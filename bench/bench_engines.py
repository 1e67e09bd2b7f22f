"""
Benchmark and cross-check of the two physics engines (PyBullet, MuJoCo) on Tasks 5 and 6.

Measures, in one run, per task:
- the designs: --designs candidates spread evenly over a seeded CMA-ES search of the task on
  PyBullet (Table I's settings, --generations x --population, --world-states worlds), those that
  are simulated (no start collision; bench_physics.searched_designs);
- speed: evaluate() per core (CPU time of this process), MuJoCo over PyBullet, on the same
  designs and worlds, in interleaved rounds, best of --rounds (target >= 2.0);
- agreement: Spearman's rank correlation of the designs' weighted-sum fitness between the
  engines (target >= 0.85);
- start collisions: the verdicts of both engines on --collision-pairs (design, world) pairs,
  designs drawn uniformly from the genome space (so both verdicts occur), one world each
  (target: agree in >= 99 %).

PD tasks (task1, task5_pd): also the MuJoCo PD law stepped in C (core.sim.mujoco_native)
against the same law stepped in Python, on the same designs, and whether the two give the same
bits (they must).

--bags BAG ...: instead, the speed ratio on the candidates recorded in each run's bag (its
task as run, e.g. Table I's 64 worlds): --speed-sample of them, spread evenly over the run.
A ratio on 8 worlds weighs the per-candidate build (a Bullet hand costs milliseconds, a
MuJoCo compile about 1.5 ms) eight times as much as one on 64. Then the same candidates in
two processes at once, per engine (wall seconds of the slower): a run's two evaluators share
the machine's two cores, its caches and memory, and an engine may suffer more from that.

Usage: python bench/bench_engines.py [--tasks task5 task6 | task1 task5_pd] [--designs 200]
       [--generations 25] [--population 16] [--world-states 8] [--speed-sample 12]
       [--rounds 3] [--collision-pairs 1000]
       python bench/bench_engines.py --bags BAG [BAG ...] [--speed-sample 12] [--rounds 3]
"""

import argparse
import concurrent.futures
import dataclasses
import multiprocessing
import os
import time

from bench_physics import searched_designs, spearman
from hand_codesign.analysis.records import open_run, recorded_design, run_task_of
from hand_codesign.core.evaluate import evaluate, evaluate_design, shared_simulator
from hand_codesign.core.sim.hand import hand_model
from hand_codesign.core.sim.mujoco_sim import MujocoSimulator
from hand_codesign.core.sim.worlds import object_state, world_states
from hand_codesign.core.task import load_task
from hand_codesign.core.task.genome import genome_spec
import numpy as np

TASKS = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'config', 'tasks')


def on_engine(task, engine):
    """Return the task simulated with `engine`."""
    return task.replace(physics=dataclasses.replace(task.physics, engine=engine))


def speed_ratio(tasks, genomes, rounds):
    """Return (PyBullet, MuJoCo) CPU seconds of evaluate() on the genomes, best of rounds."""
    seconds = np.zeros(2)
    for x in genomes:
        best = np.full(2, np.inf)
        for _ in range(rounds):
            for index, task in enumerate(tasks):
                start = time.process_time()
                evaluate(x, task)
                best[index] = min(best[index], time.process_time() - start)
        seconds += best
    return seconds


def pd_law_ratio(task, genomes, rounds):
    """Return (Python law s, C law s, same bits) of MuJoCo evaluations, best of rounds each."""
    spec = genome_spec(task)
    seconds, same = np.zeros(2), True
    with MujocoSimulator() as python, MujocoSimulator() as native:
        python.native = False
        for x in genomes:
            design, best, results = spec.decode(x), np.full(2, np.inf), []
            for _ in range(rounds):
                for index, simulator in enumerate((python, native)):
                    start = time.process_time()
                    results.append(evaluate_design(design, task, simulator=simulator))
                    best[index] = min(best[index], time.process_time() - start)
            seconds += best
            same &= all(np.array_equal(result.world_objectives, results[0].world_objectives)
                        and np.array_equal(result.final_poses, results[0].final_poses)
                        for result in results)
    return seconds[0], seconds[1], same


def collision_agreement(task, pairs, seed=5):
    """Return (agreeing pairs, pairs, colliding pairs on PyBullet) of start-collision checks."""
    spec = genome_spec(task)
    generator = np.random.default_rng(seed)
    states = [object_state(task, world) for world in world_states(task, pairs)]
    simulators = [shared_simulator('pybullet'), shared_simulator('mujoco')]
    agree = colliding = 0
    for state in states:
        model = hand_model(spec.decode(generator.random(spec.size)).hand, task.hand)
        verdicts = []
        for simulator in simulators:
            simulator.build(task, model)
            shape = simulator.object_shape(state, task.object_spec.shape)
            verdicts.append(simulator.start_collisions([(state, shape)]))
        agree += verdicts[0] == verdicts[1]
        colliding += verdicts[0]
    return agree, len(states), colliding


def bench_task(name, arguments):
    """Print the figures of one task."""
    reference = load_task(os.path.join(TASKS, name + '.yaml')).replace(
        num_world_states=arguments.world_states, population=arguments.population, seed=1,
        iterations=10 ** 6)
    mujoco = on_engine(reference, 'mujoco')
    started = time.perf_counter()
    genomes, bullet_fitness = searched_designs(reference, arguments.generations,
                                               arguments.designs)
    mujoco_results = [evaluate(x, mujoco) for x in genomes]
    mujoco_fitness = np.array([result.fitness for result in mujoco_results])
    unstable = sum(result.unstable_worlds > 0 for result in mujoco_results)
    sample = genomes[::max(1, len(genomes) // arguments.speed_sample)][:arguments.speed_sample]
    bullet_seconds, mujoco_seconds = speed_ratio((reference, mujoco), sample, arguments.rounds)
    law = (pd_law_ratio(mujoco, sample, arguments.rounds) if reference.policy.kind == 'pd'
           else None)
    agree, pairs, colliding = collision_agreement(reference, arguments.collision_pairs)
    print(f'{name}: {len(genomes)} designs from {arguments.generations} x {arguments.population} '
          f'CMA-ES on PyBullet, {arguments.world_states} worlds each '
          f'({time.perf_counter() - started:.0f} s)')
    print(f'  evaluate() per core, MuJoCo over PyBullet: {bullet_seconds / mujoco_seconds:.2f} '
          f'(PyBullet {bullet_seconds / len(sample) * 1e3:.1f} ms, MuJoCo '
          f'{mujoco_seconds / len(sample) * 1e3:.1f} ms per evaluation, {len(sample)} designs, '
          f'best of {arguments.rounds})')
    if law is not None:
        print(f'  MuJoCo PD law in C over the law in Python: {law[0] / law[1]:.2f} '
              f'({law[0] / len(sample) * 1e3:.1f} and {law[1] / len(sample) * 1e3:.1f} ms per '
              f'evaluation; bit-identical: {"yes" if law[2] else "NO"})')
    print(f'  Spearman rank correlation of the weighted sum between engines: '
          f'{spearman(bullet_fitness, mujoco_fitness):.3f} (designs unstable on MuJoCo: '
          f'{unstable}); median fitness PyBullet {np.median(bullet_fitness):.4f}, '
          f'MuJoCo {np.median(mujoco_fitness):.4f}')
    print(f'  start-collision verdicts agree: {agree} of {pairs} (design, world) pairs '
          f'({agree / pairs * 100:.1f} %; {colliding} collide on PyBullet)')


def bench_bag(bag, arguments):
    """Print the speed ratio on candidates recorded in a run's bag, on its task as run."""
    record = open_run(bag, warn=False)
    reference = run_task_of(record)
    ids = np.unique(np.asarray(record.candidates['candidate_id'], dtype=np.int64))
    chosen = ids[np.linspace(0, len(ids) - 1, arguments.speed_sample).round().astype(int)]
    genomes = [recorded_design(record, int(candidate)).x for candidate in chosen]
    tasks = (on_engine(reference, 'pybullet'), on_engine(reference, 'mujoco'))
    bullet_seconds, mujoco_seconds = speed_ratio(tasks, genomes, arguments.rounds)
    worlds = len(genomes) * reference.num_world_states
    print(f'{bag}: {len(genomes)} recorded candidates (ids {chosen[0]} to {chosen[-1]}), '
          f'{reference.num_world_states} worlds each, ran on {reference.physics.engine}')
    print(f'  evaluate() per core, MuJoCo over PyBullet: {bullet_seconds / mujoco_seconds:.2f} '
          f'(PyBullet {bullet_seconds / worlds * 1e3:.2f} ms, MuJoCo '
          f'{mujoco_seconds / worlds * 1e3:.2f} ms per world, best of {arguments.rounds})')
    pair = [two_at_once(task, genomes, arguments.rounds) for task in tasks]
    print(f'  two processes at once, MuJoCo over PyBullet: {pair[0] / pair[1]:.2f} (PyBullet '
          f'{pair[0] / worlds * 1e3:.2f} ms, MuJoCo {pair[1] / worlds * 1e3:.2f} ms per world '
          'and process, wall time)')


def wall_seconds(task, genomes):
    """Return the wall seconds of evaluate() over the genomes (after one to warm up)."""
    evaluate(genomes[0], task)
    start = time.perf_counter()
    for x in genomes:
        evaluate(x, task)
    return time.perf_counter() - start


def two_at_once(task, genomes, rounds):
    """Return the wall seconds of two processes evaluating the genomes at once, best round."""
    spawn = multiprocessing.get_context('spawn')
    with concurrent.futures.ProcessPoolExecutor(2, mp_context=spawn) as pool:
        return min(max(pool.map(wall_seconds, [task] * 2, [genomes] * 2))
                   for _ in range(rounds))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--tasks', nargs='+', default=['task5', 'task6'])
    parser.add_argument('--designs', type=int, default=200)
    parser.add_argument('--generations', type=int, default=25)
    parser.add_argument('--population', type=int, default=16)
    parser.add_argument('--world-states', type=int, default=8)
    parser.add_argument('--speed-sample', type=int, default=12)
    parser.add_argument('--rounds', type=int, default=3)
    parser.add_argument('--collision-pairs', type=int, default=1000)
    parser.add_argument('--bags', nargs='+', default=[],
                        help='measure the speed on the candidates recorded in these runs')
    arguments = parser.parse_args()
    for bag in arguments.bags:
        bench_bag(bag, arguments)
    for name in [] if arguments.bags else arguments.tasks:
        bench_task(name, arguments)


if __name__ == '__main__':
    main()
