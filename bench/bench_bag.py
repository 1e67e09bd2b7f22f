"""
Benchmark of the bag layer: our code against the libraries, on one big bag, in one process.

Writes a bag of N evaluations (default 100,000: with as many candidates and one generation
summary per population, about 200,000 messages) of Task 5 with BagWriter, then times on that
same file:

- reading the records (every message's bytes, by type): read_run's reader (mcap's
  ``StreamReader`` with the chunks broken up by ``bag.scan_file``), mcap's ``StreamReader``
  alone and rosbags' ``AnyReader`` (which needs a complete file: a killed recorder's bag it
  refuses);
- decoding the loop messages into field tuples: ours (``cdr.compile_schema``), the rosbags
  typestore built from the bag's schemas, and mcap-ros2-support;
- the whole read: ``read_run`` (into column tables) against rosbags (AnyReader and typestore)
  and against mcap with mcap-ros2-support (decoding only).

Each line prints the seconds of the fastest of --repeat runs and the ratio to the first line of
its group (above 1: slower than the first). Run:

    python bench/bench_bag.py [--evaluations N] [--repeat R] [--keep PATH]
"""

import argparse
import collections
import operator
import os
import pathlib
import sys
import tempfile
import time

from hand_codesign.bag import cdr
from hand_codesign.bag import reader as bag
from hand_codesign.bag.writer import BagWriter
from hand_codesign.core import genome_spec
from hand_codesign.core import load_task
from hand_codesign.core import objective_names
from hand_codesign.ros import topics
from hand_codesign_msgs.msg import Candidate
from hand_codesign_msgs.msg import Evaluation
from hand_codesign_msgs.msg import GenerationSummary
from hand_codesign_msgs.msg import RunInfo
from mcap.reader import make_reader
from mcap.records import Channel
from mcap.records import Message
from mcap.records import Schema
from mcap.stream_reader import StreamReader
from mcap_ros2.decoder import DecoderFactory
import numpy as np
from rclpy.serialization import serialize_message
from rosbags.highlevel import AnyReader
from rosbags.typesys import get_types_from_msg
from rosbags.typesys import get_typestore
from rosbags.typesys import Stores

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
    told = []
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
            told.append(objectives)
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
                    best_genome=genome.tolist(),
                    told_ids=list(range(candidate_id + 1 - population, candidate_id + 1)),
                    told_objectives=np.ravel(told).tolist(), evaluations=candidate_id + 1)))
                told.clear()
        return writer.message_count


# ---------------------------------------------------------------- reading the records

def records_read_run(path):
    """Return {schema name: [message bytes]} read as read_run reads them."""
    scan = bag.scan_file(path)
    messages = collections.defaultdict(list)
    for channel_id, rows in scan.messages.items():
        messages[scan.channels[channel_id].schema_name].extend(data for _, _, data in rows)
    return messages


def records_mcap(path):
    """Return {schema name: [message bytes]} read front to back by mcap's StreamReader."""
    schemas, channels = {}, {}
    messages = collections.defaultdict(list)
    with open(path, 'rb') as stream:
        for record in StreamReader(stream).records:
            if isinstance(record, Message):
                messages[channels[record.channel_id]].append(record.data)
            elif isinstance(record, Schema):
                schemas[record.id] = record.name
            elif isinstance(record, Channel):
                channels[record.id] = schemas.get(record.schema_id, '')
    return messages


def records_rosbags(path):
    """Return {schema name: [message bytes]} read by rosbags' AnyReader."""
    messages = collections.defaultdict(list)
    with AnyReader([pathlib.Path(path)]) as reader:
        for connection, _, data in reader.messages():
            messages[connection.msgtype].append(data)
    return messages


# ---------------------------------------------------------------- decoding

def schemas_of(path):
    """Return {schema name: ros2msg text} of the bag."""
    with open(path, 'rb') as stream:
        summary = make_reader(stream).get_summary()
    return {schema.name: schema.data.decode() for schema in summary.schemas.values()}


def decode_ours(schemas, messages):
    """Decode with the decoders compiled from the schema text; return the message count."""
    count = 0
    for name, rows in messages.items():
        decode = cdr.compile_schema(name, schemas[name])
        count += len([decode(data) for data in rows])
    return count


def decode_rosbags(schemas, messages):
    """Decode with a rosbags typestore built from the bag's schemas, into field tuples."""
    store = get_typestore(Stores.EMPTY)
    for name, text in schemas.items():
        store.register(get_types_from_msg(text, name))
    count = 0
    for name, rows in messages.items():
        fields = operator.attrgetter(*cdr.field_names(name, schemas[name]))
        deserialize = store.deserialize_cdr
        count += len([fields(deserialize(data, name)) for data in rows])
    return count


def decode_mcap_ros2(schemas, messages):
    """Decode with mcap-ros2-support's generic decoder, into field tuples."""
    count = 0
    for name, rows in messages.items():
        decode = DecoderFactory().decoder_for(
            'cdr', Schema(id=1, name=name, encoding='ros2msg', data=schemas[name].encode()))
        fields = operator.attrgetter(*cdr.field_names(name, schemas[name]))
        count += len([fields(decode(data)) for data in rows])
    return count


# ---------------------------------------------------------------- whole reads

def read_rosbags(path):
    """Read and decode every message with rosbags alone; return the message count."""
    count = 0
    with AnyReader([pathlib.Path(path)]) as reader:
        for connection, _, data in reader.messages():
            reader.deserialize(data, connection.msgtype)
            count += 1
    return count


def read_mcap_ros2(path):
    """Decode every message with mcap + mcap-ros2-support; return the message count."""
    with open(path, 'rb') as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        return sum(1 for _ in reader.iter_decoded_messages())


REPEAT = [3]


def timed(function, *arguments):
    """Return (seconds, result) of the fastest of REPEAT calls (the machine may be shared)."""
    best = None
    for _ in range(REPEAT[0]):
        start = time.perf_counter()
        result = function(*arguments)
        seconds = time.perf_counter() - start
        best = seconds if best is None else min(best, seconds)
    return best, result


def report(label, seconds, first):
    """Print one line: seconds and how many times longer than the first of its group."""
    print(f'  {label:<44} {seconds:6.2f} s   ratio to the first line: {seconds / first:5.2f}')


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--evaluations', type=int, default=100_000)
    parser.add_argument('--keep', help='write the bag here and keep it')
    parser.add_argument('--repeat', type=int, default=3, help='time the best of this many')
    options = parser.parse_args()
    REPEAT[0] = options.repeat
    directory = tempfile.TemporaryDirectory()
    path = pathlib.Path(options.keep or os.path.join(directory.name, 'bench.mcap'))

    start = time.perf_counter()
    count = write_run(path, options.evaluations)
    seconds = time.perf_counter() - start
    print(f'bag: {count} messages ({options.evaluations} evaluations), '
          f'{path.stat().st_size / 1e6:.1f} MB, written in {seconds:.2f} s')

    print('reading the records (bytes of every message, by type):')
    first, messages = timed(records_read_run, path)
    report("read_run's reader (bag.scan_file)", first, first)
    for label, function in (('mcap StreamReader alone', records_mcap),
                            ('rosbags AnyReader', records_rosbags)):
        seconds, theirs = timed(function, path)
        assert sum(map(len, theirs.values())) == count, label
        report(label, seconds, first)

    print('decoding the messages into field tuples:')
    schemas = schemas_of(path)
    ours, decoded = timed(decode_ours, schemas, messages)
    assert decoded == count
    report('ours (cdr.compile_schema)', ours, ours)
    for label, function in (('rosbags typestore from the bag schemas', decode_rosbags),
                            ('mcap-ros2-support', decode_mcap_ros2)):
        seconds, decoded = timed(function, schemas, messages)
        assert decoded == count, label
        report(label, seconds, ours)

    print('the whole read:')
    ours, record = timed(bag.read_run, path)
    assert len(record.evaluations) == options.evaluations, record.warning
    report('read_run (into column tables)', ours, ours)
    for label, function in (('rosbags AnyReader + deserialize', read_rosbags),
                            ('mcap + mcap-ros2-support', read_mcap_ros2)):
        seconds, decoded = timed(function, path)
        assert decoded == count, label
        report(label, seconds, ours)
    directory.cleanup()
    return 0


if __name__ == '__main__':
    sys.exit(main())
