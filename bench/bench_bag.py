"""
Benchmark of the bag layer: writing a big run with BagWriter and reading it with read_run.

Writes a bag of N evaluations (default 100,000, the analyze budget of issue 6) of Task 5 with
as many candidates, one generation summary per population and the RunInfo, then reads it back
with ``read_run``. The reference, measured in the same run on the same file, is the generic
route: mcap's reader with mcap-ros2-support decoding every message.

    python bench/bench_bag.py [--evaluations N] [--keep PATH]
"""

import argparse
import os
import pathlib
import sys
import tempfile
import time

from hand_codesign.analysis.bag import read_run
from hand_codesign.core import genome_spec
from hand_codesign.core import load_task
from hand_codesign.core import objective_names
from hand_codesign.ros import topics
from hand_codesign.ros.mcap_writer import BagWriter
from hand_codesign_msgs.msg import Candidate
from hand_codesign_msgs.msg import Evaluation
from hand_codesign_msgs.msg import GenerationSummary
from hand_codesign_msgs.msg import RunInfo
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
import numpy as np
from rclpy.serialization import serialize_message

ROOT = pathlib.Path(__file__).resolve().parents[1]
TASK = ROOT / 'config' / 'tasks' / 'task5.yaml'


def write_run(path, evaluations):
    """Write a run of evaluations candidates and evaluations; return the message count."""
    task = load_task(TASK)
    spec = genome_spec(task)
    names = objective_names(task)
    worlds = task.num_world_states
    population = task.population
    rng = np.random.default_rng(0)
    run_id = 'bench-run'
    with BagWriter(path) as writer:
        for topic in (topics.RUN_INFO, topics.CANDIDATES, topics.EVALUATIONS,
                      topics.GENERATION_SUMMARY):
            writer.add_topic('/' + topic, topics.type_name(topics.MESSAGE_TYPES[topic]),
                             [topics.QOS[topic]])
        writer.write('/run_info', serialize_message(RunInfo(
            run_id=run_id, task_name=task.name, task_yaml=task.source_text, seed=task.seed,
            algorithm=task.algorithm, iterations=evaluations // population,
            population=population, world_states=worlds, objective_names=names)))
        for candidate_id in range(evaluations):
            generation = candidate_id // population
            genome = rng.random(spec.size)
            writer.write('/candidates', serialize_message(Candidate(
                run_id=run_id, generation=generation, candidate_id=candidate_id,
                structure=list(task.structure), genome=genome.tolist(),
                genome_names=list(spec.names))))
            world = rng.random((worlds, len(names)))
            objectives = world.mean(axis=0)
            writer.write('/evaluations', serialize_message(Evaluation(
                run_id=run_id, generation=generation, candidate_id=candidate_id,
                evaluator_id=f'host-{candidate_id % 2}', objectives=objectives.tolist(),
                objective_names=names, fitness=float(objectives @ task.objective_weights),
                simulated_time=10.0, wall_time=0.3, world_objectives=world.ravel().tolist())))
            if (candidate_id + 1) % population == 0:
                writer.write('/generation_summary', serialize_message(GenerationSummary(
                    run_id=run_id, generation=generation, structure=list(task.structure),
                    objective_names=names, best=objectives.tolist(),
                    median=objectives.tolist(), worst=objectives.tolist(),
                    best_candidate_id=candidate_id, best_objectives=objectives.tolist(),
                    best_genome=genome.tolist(), evaluations=candidate_id + 1)))
        return writer.message_count


def read_generic(path):
    """Decode every message with mcap + mcap-ros2-support; return the message count."""
    with open(path, 'rb') as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        return sum(1 for _ in reader.iter_decoded_messages())


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--evaluations', type=int, default=100_000)
    parser.add_argument('--keep', help='write the bag here and keep it')
    options = parser.parse_args()
    directory = tempfile.TemporaryDirectory()
    path = pathlib.Path(options.keep or os.path.join(directory.name, 'bench.mcap'))

    start = time.perf_counter()
    count = write_run(path, options.evaluations)
    write_seconds = time.perf_counter() - start
    size = path.stat().st_size

    start = time.perf_counter()
    record = read_run(path)
    read_seconds = time.perf_counter() - start
    assert len(record.evaluations) == options.evaluations, record.warning

    start = time.perf_counter()
    generic_count = read_generic(path)
    generic_seconds = time.perf_counter() - start
    assert generic_count == count

    print(f'bag: {count} messages ({options.evaluations} evaluations), {size / 1e6:.1f} MB')
    print(f'write (serialize + BagWriter): {write_seconds:.2f} s, '
          f'{count / write_seconds:.0f} messages/s')
    print(f'read_run:                      {read_seconds:.2f} s, '
          f'{count / read_seconds:.0f} messages/s')
    print(f'mcap + mcap-ros2-support:      {generic_seconds:.2f} s, '
          f'{count / generic_seconds:.0f} messages/s (reference)')
    print(f'ratio read_run / reference speed: {generic_seconds / read_seconds:.2f}')
    directory.cleanup()
    return 0


if __name__ == '__main__':
    sys.exit(main())
