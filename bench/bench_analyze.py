"""
Benchmark: `hand-codesign analyze` on a bag of 100,000 evaluations (the goal: under 30 s).

Writes a bag the way the recorder does (BagWriter, zstd chunks, CDR from rclpy) of a Task 5
run of 1,250 generations of 80 candidates on 8 world states: RunInfo, 100,000 candidates,
100,000 evaluations (a few rejected and duplicated), heartbeats and 1,250 generation
summaries. Then it times, in the same process:

- the reference: merely reading the bag into tables (`bag.read_run`);
- `analyze` as the CLI runs it (read, join, CSV of every evaluation, plots, report.md).

Run: python bench/bench_analyze.py [--evaluations N] [--keep DIR]
"""

import argparse
import contextlib
import io
import pathlib
import sys
import tempfile
import time

from hand_codesign.bag.reader import read_run
from hand_codesign.bag.writer import BagWriter
from hand_codesign.cli import main as cli_main
from hand_codesign.core.run.runs import run_task
from hand_codesign.core.task import load_task
from hand_codesign.core.task.genome import genome_spec
from hand_codesign.ros import topics
from hand_codesign_msgs.msg import Candidate
from hand_codesign_msgs.msg import Evaluation
from hand_codesign_msgs.msg import EvaluatorStatus
from hand_codesign_msgs.msg import GenerationSummary
from hand_codesign_msgs.msg import RunInfo
import numpy as np
from rclpy.serialization import serialize_message

ROOT = pathlib.Path(__file__).resolve().parents[1]
TASK_FILE = ROOT / 'config' / 'tasks' / 'task5.yaml'
GOAL_SECONDS = 30.0


def write_bag(path, evaluations, population=80, worlds=8, seed=0):
    """Write a bag of a synthetic Task 5 run with `evaluations` evaluations; return its path."""
    base = load_task(str(TASK_FILE))
    generations = -(-evaluations // population)
    task = run_task(base.source_text, str(TASK_FILE), seed, generations, population, worlds)
    names = genome_spec(task).names
    objective_names = list(task.objective_names)
    run_id = 'bench-run'
    rng = np.random.default_rng(seed)
    writer = BagWriter(str(path))
    for topic in topics.MESSAGE_TYPES:
        writer.add_topic('/' + topic, topics.type_name(topics.MESSAGE_TYPES[topic]),
                         [topics.QOS[topic]])
    clock = [1_700_000_000 * 10 ** 9]

    def write(topic, message):
        clock[0] += 1000
        writer.write('/' + topic, serialize_message(message), log_time=clock[0])

    write(topics.RUN_INFO, RunInfo(
        run_id=run_id, task_name=task.name, task_yaml=task.source_text, seed=seed,
        algorithm=task.algorithm, iterations=generations, population=population,
        world_states=worlds, objective_names=objective_names,
        versions=['hand_codesign==bench']))
    best_fitness, best_id, best_x = np.inf, 0, None
    told = 0
    for generation in range(generations):
        genomes = rng.normal(0.5, 0.1, (population, len(names)))
        world = rng.random((population, worlds, len(objective_names))) * 0.02
        objectives = world.mean(axis=1)
        fitness = objectives @ task.objective_weights
        ids = np.arange(population, dtype=np.uint64) + generation * population
        for index in range(population):
            write(topics.CANDIDATES, Candidate(
                run_id=run_id, generation=generation, candidate_id=int(ids[index]),
                evaluator_id=f'evaluator-{index % 2}', structure=list(task.structure),
                genome=genomes[index].tolist(), genome_names=names))
        for index in range(population):
            if told + index >= evaluations:
                break
            message = Evaluation(
                run_id=run_id, generation=generation, candidate_id=int(ids[index]),
                evaluator_id=f'evaluator-{index % 2}', status=Evaluation.STATUS_OK,
                objectives=objectives[index].tolist(), objective_names=objective_names,
                fitness=float(fitness[index]), collision=bool(index == 7),
                unstable_worlds=int(index == 11), simulated_time=1.5 * worlds,
                wall_time=0.1, world_objectives=world[index].ravel().tolist())
            write(topics.EVALUATIONS, message)
            if index == 3 and generation % 50 == 0:
                write(topics.EVALUATIONS, message)     # a duplicate answer
        if generation % 10 == 0:
            write(topics.EVALUATOR_STATUS, EvaluatorStatus(
                evaluator_id='evaluator-0', run_id=run_id, host='bench', pid=1, capacity=2,
                load=1, evaluations_done=told, steps_per_second=25000.0))
        told += population
        best = int(np.argmin(fitness))
        if fitness[best] < best_fitness:
            best_fitness, best_id, best_x = float(fitness[best]), int(ids[best]), genomes[best]
        write(topics.GENERATION_SUMMARY, GenerationSummary(
            run_id=run_id, generation=generation, structure=list(task.structure),
            objective_names=objective_names, best=objectives.min(axis=0).tolist(),
            median=np.median(objectives, axis=0).tolist(),
            worst=objectives.max(axis=0).tolist(), best_candidate_id=best_id,
            best_objectives=objectives[best].tolist(), best_fitness=best_fitness,
            best_genome=best_x.tolist(), told_ids=ids.tolist(),
            told_objectives=objectives.ravel().tolist(), evaluations=told,
            wall_time=0.5 * (generation + 1), final=generation == generations - 1,
            stop_reason='maxiter' if generation == generations - 1 else ''))
    writer.close()
    return path


def timed(function):
    started = time.perf_counter()
    result = function()
    return time.perf_counter() - started, result


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--evaluations', type=int, default=100_000)
    parser.add_argument('--keep', help='write the bag and report here instead of a temp dir')
    arguments = parser.parse_args(argv)
    with contextlib.ExitStack() as stack:
        folder = pathlib.Path(arguments.keep or stack.enter_context(tempfile.TemporaryDirectory()))
        folder.mkdir(parents=True, exist_ok=True)
        bag = folder / 'bench_bag'
        seconds, _ = timed(lambda: write_bag(bag, arguments.evaluations))
        size = sum(file.stat().st_size for file in bag.glob('*.mcap'))
        print(f'wrote a bag of {arguments.evaluations} evaluations in {seconds:.1f} s '
              f'({size / 1e6:.1f} MB)')
        read_seconds, record = timed(lambda: read_run(bag))
        print(f'reference, read_run: {read_seconds:.2f} s ({len(record.evaluations)} '
              f'evaluations, {len(record.candidates)} candidates)')
        terminal = io.StringIO()
        with contextlib.redirect_stdout(terminal):
            analyze_seconds, code = timed(lambda: cli_main(
                ['analyze', str(bag), '--out', str(folder / 'report')]))
        if code != 0:
            print(terminal.getvalue())
            print(f'analyze failed with exit code {code}')
            return 1
        lines = sum(1 for _ in open(folder / 'report' / 'evaluations.csv')) - 1
        verdict = 'met' if analyze_seconds < GOAL_SECONDS else 'MISSED'
        print(f'analyze: {analyze_seconds:.2f} s ({lines} CSV rows); '
              f'{analyze_seconds / read_seconds:.2f}x the time to read the bag; '
              f'goal < {GOAL_SECONDS:.0f} s: {verdict}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
