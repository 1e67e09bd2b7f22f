"""
Benchmark of the profile-optimized PyBullet (tools/build_pybullet.py) against the PyPI wheel.

Both extension modules step the very same Task 5 candidates in one run of this script, each in
its own process (a module is chosen by putting its folder first on PYTHONPATH), alternately,
so that the machine's load falls on both alike. Prints, built over wheel:
- the bare loop (bench_core's: the candidate's built worlds stepped with its torques, nothing
  else; the issue's reference "today's bare loop"): the ratio of stepping rates (target >= 1.3);
- evaluate() (build, checks, rollouts, objectives: what an evaluator does per candidate);
- whether the objectives of every candidate and world are bit-identical (they must be).
Times are each process's CPU time, the fastest of the rounds per candidate.

The candidates: drawn around the search's start as bench_core draws them, or with --bag those
a Task 5 run evaluated (a sample of its simulated candidates: later generations touch the box
more and step slower than the first).

Usage: python bench/bench_pybullet_build.py [--candidates 12] [--rounds 3] [--bag BAG]
                                           [--built FOLDER]
(--built: compare the module in FOLDER, another build, instead of the installed one)
"""

import argparse
import hashlib
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / 'tools'))

import build_pybullet  # noqa: E402, I100: a tool script, not a package
import numpy as np  # noqa: E402, I100

TASK_FILE = ROOT / 'config' / 'tasks' / 'task5.yaml'


def worker(genomes_file, rounds):
    """In the child process: time the bare loop and evaluate() per candidate; print JSON."""
    from bench_core import bare_loop
    from hand_codesign.core.evaluate import evaluate, shared_simulator
    from hand_codesign.core.sim.objectives import goal_schedule
    from hand_codesign.core.task import load_task
    import pybullet
    task = load_task(TASK_FILE)
    simulator = shared_simulator()
    bare = evaluation = 0.0
    steps = 0
    # the bare loop steps every world to the end; evaluate() stops a world early (eq. 6)
    bare_steps_per_candidate = task.num_world_states * simulator.plan(
        goal_schedule(task)).num_steps
    genomes = np.load(genomes_file)
    digest = hashlib.sha256()
    for x in genomes:
        best_bare = best_evaluation = float('inf')
        for _ in range(rounds):
            best_bare = min(best_bare, bare_loop(task, x, simulator, True))
            start = time.process_time()
            result = evaluate(x, task)
            best_evaluation = min(best_evaluation, time.process_time() - start)
        bare += best_bare
        evaluation += best_evaluation
        steps += round(result.simulated_time / task.time_step)
        digest.update(np.ascontiguousarray(result.world_objectives).tobytes())
        digest.update(np.ascontiguousarray(result.objectives).tobytes())
    print(json.dumps({'module': pybullet.__file__, 'bare': bare, 'evaluate': evaluation,
                      'steps': {'bare': bare_steps_per_candidate * len(genomes),
                                'evaluate': steps},
                      'objectives': digest.hexdigest()}))


def measure(module_folder, genomes_file, rounds):
    """Run the worker with PyBullet's module taken from `module_folder` (None: installed)."""
    paths = [str(ROOT / 'bench')] + ([str(module_folder)] if module_folder else [])
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(paths))
    output = subprocess.run([sys.executable, __file__, '--worker', str(genomes_file),
                             '--rounds', str(rounds)], env=env, check=True,
                            capture_output=True, text=True).stdout
    return json.loads(output.splitlines()[-1])


def chosen_genomes(arguments):
    """Return the benchmark's candidates: from --bag, or drawn as bench_core draws them."""
    from hand_codesign.core.task import load_task
    task = load_task(TASK_FILE)
    if arguments.bag is None:
        from bench_core import candidates
        return np.array(candidates(task, arguments.candidates, seed=1))
    from hand_codesign.bag.reader import read_run
    record = read_run(arguments.bag)
    evaluations = record.evaluations.select((record.evaluations['status'] == 0)
                                            & (record.evaluations['simulated_time'] > 0))
    genomes = dict(zip(record.candidates['candidate_id'], record.candidates['genome']))
    chosen = np.random.default_rng(0).choice(evaluations['candidate_id'],
                                             arguments.candidates, replace=False)
    return np.array([genomes[i] for i in chosen])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--candidates', type=int, default=12)
    parser.add_argument('--rounds', type=int, default=3, help='rounds per candidate, per turn')
    parser.add_argument('--turns', type=int, default=2, help='alternate processes per module')
    parser.add_argument('--bag', help='take the candidates from this Task 5 run')
    parser.add_argument('--built', help='folder of another built module to compare')
    parser.add_argument('--worker', help=argparse.SUPPRESS)
    arguments = parser.parse_args()
    if arguments.worker:
        worker(arguments.worker, arguments.rounds)
        return
    wheel = build_pybullet.wheel_copy()
    if not wheel.exists():
        print(f'no wheel copy at {wheel}: the installed PyBullet is the wheel '
              '(run `make fast-physics` first); nothing to compare')
        return
    sys.path.insert(0, str(ROOT / 'bench'))
    with tempfile.TemporaryDirectory() as folder:
        genomes_file = pathlib.Path(folder) / 'genomes.npy'
        np.save(genomes_file, chosen_genomes(arguments))
        runs = {'wheel': [], 'built': []}
        for _ in range(arguments.turns):
            runs['wheel'].append(measure(wheel.parent, genomes_file, arguments.rounds))
            runs['built'].append(measure(arguments.built, genomes_file, arguments.rounds))
    best = {name: {key: min(run[key] for run in turns) for key in ('bare', 'evaluate')}
            for name, turns in runs.items()}
    steps = runs['wheel'][0]['steps']
    identical = len({run['objectives'] for turns in runs.values() for run in turns}) == 1
    print(f'Task 5, {arguments.candidates} candidates x 8 worlds, {steps["evaluate"]} steps '
          f'evaluated ({steps["bare"]} in the bare loop, which never stops early); fastest of '
          f'{arguments.rounds} rounds x {arguments.turns} alternate processes per module; '
          f'load {os.getloadavg()[0]:.1f}')
    print(f'  wheel: {runs["wheel"][0]["module"]}')
    print(f'  built: {runs["built"][0]["module"]}')
    for key, label in (('bare', 'bare loop, same torques'), ('evaluate', 'evaluate()')):
        wheel_rate, built_rate = (steps[key] / best[name][key] for name in ('wheel', 'built'))
        print(f'{label:26s} built / wheel   {built_rate / wheel_rate:.3f}   '
              f'({built_rate:,.0f} against {wheel_rate:,.0f} steps/s)'
              + ('  (target >= 1.3)' if key == 'bare' else ''))
    print(f'objectives of every candidate and world bit-identical: {"yes" if identical else "NO"}')


if __name__ == '__main__':
    main()
