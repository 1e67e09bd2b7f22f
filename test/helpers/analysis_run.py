"""
One short real run shared by the analysis tests, and helpers to read and rewrite its bag.

`real_run` (session scope, registered in conftest.py) runs `hand-codesign run` once as a user
does, with real processes over DDS: Task 5, 2 evaluators, 4 generations of 6 candidates on 2
world states, seed 3 (about 15 s). Tests must not modify its folder; they copy what they
change.
"""

import dataclasses
import json
import pathlib
import subprocess
import sys

from hand_codesign.bag.writer import BagWriter
from hand_codesign.ros import topics
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
import pytest
from rclpy.serialization import deserialize_message
from rclpy.serialization import serialize_message

ROOT = pathlib.Path(__file__).resolve().parents[2]
TASK = ROOT / 'config' / 'tasks' / 'task5.yaml'
BUDGET = ['--iterations', '4', '--population', '6', '--world-states', '2', '--seed', '3']
# what the `hand-codesign` console script runs
CLI = [sys.executable, '-c', 'import sys; from hand_codesign.cli import main; sys.exit(main())']


@dataclasses.dataclass
class RealRun:
    """A finished run: its bag folder, the .mcap file in it and its result.json."""

    bag: pathlib.Path
    mcap: pathlib.Path
    result: dict


def run_codesign(bag, budget=BUDGET, extra=(), timeout=300, task=TASK):
    """Run `hand-codesign run` to completion; return its output (assert it succeeded)."""
    command = CLI + ['run', '--task', str(task), '--evaluators', '2', '--bag', str(bag),
                     '--domain-id', 'auto', *budget, *extra]
    process = subprocess.run(command, cwd=ROOT, stdout=subprocess.PIPE,
                             stderr=subprocess.STDOUT, text=True, timeout=timeout)
    assert process.returncode == 0, process.stdout
    return process.stdout


@pytest.fixture(scope='session')
def real_run(tmp_path_factory):
    """Return the RealRun of one short `hand-codesign run` (made once per test session)."""
    bag = tmp_path_factory.mktemp('real_run') / 'task5_run'
    run_codesign(bag)
    mcap_files = sorted(bag.glob('*.mcap'))
    assert len(mcap_files) == 1, list(bag.iterdir())
    return RealRun(bag=bag, mcap=mcap_files[0],
                   result=json.loads((bag / 'result.json').read_text()))


def run_cli(*arguments, timeout=300):
    """Run the hand-codesign CLI in a new process; return the CompletedProcess (text)."""
    return subprocess.run(CLI + [str(argument) for argument in arguments], cwd=ROOT,
                          capture_output=True, text=True, timeout=timeout)


def raw_messages(mcap_path):
    """Return [(topic without '/', log_time, publish_time, CDR bytes)] of a bag file."""
    with open(mcap_path, 'rb') as stream:
        return [(channel.topic.lstrip('/'), message.log_time, message.publish_time,
                 message.data)
                for _, channel, message in make_reader(stream).iter_messages()]


def decoded_messages(mcap_path, topic):
    """Return the messages of one topic decoded by mcap-ros2-support (independent reader)."""
    with open(mcap_path, 'rb') as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        return [decoded for _, channel, _, decoded in reader.iter_decoded_messages()
                if channel.topic.lstrip('/') == topic]


def until_evaluation_of(candidate_id):
    """
    Return a copy_bag `keep` that ends the bag after the evaluation of `candidate_id`.

    As a run interrupted there leaves it: everything before, nothing after.
    """
    state = {'cut': False}

    def keep(topic, log_time, message):
        if state['cut']:
            return False
        if topic == topics.EVALUATIONS and message.candidate_id >= candidate_id:
            state['cut'] = True
        return True
    return keep


def copy_bag(source_mcap, destination, keep=None, edit=None, extra=(), first=()):
    """
    Write a copy of a bag file to destination (.mcap) with BagWriter, as the recorder would.

    keep(topic, log_time, message) -> bool drops messages; edit(topic, message) changes the
    decoded rclpy message in place before it is written; extra: (topic, rclpy message) pairs
    written after the copied messages, each a millisecond after the last; first: (topic, rclpy
    message, log time, publish time) written before them.
    """
    writer = BagWriter(str(destination))
    for topic, message_class in topics.RECORDED_MESSAGE_TYPES.items():
        writer.add_topic('/' + topic, topics.type_name(message_class), [topics.QOS[topic]])
    for topic, message, log_time, publish_time in first:
        writer.write('/' + topic, serialize_message(message), log_time=log_time,
                     publish_time=publish_time)
    for topic, log_time, publish_time, data in raw_messages(source_mcap):
        message = deserialize_message(data, topics.RECORDED_MESSAGE_TYPES[topic])
        if keep is not None and not keep(topic, log_time, message):
            continue
        if edit is not None and edit(topic, message):
            data = serialize_message(message)
        writer.write('/' + topic, data, log_time=log_time, publish_time=publish_time)
    for topic, message in extra:
        log_time += 1_000_000
        writer.write('/' + topic, serialize_message(message), log_time=log_time,
                     publish_time=log_time)
    writer.close()
    return pathlib.Path(destination)
