"""The recorder process records every message of the loop and leaves a readable bag."""

import pathlib
import random
import signal
import sys
import textwrap
import time
import uuid

from bag_samples import Process
from bag_samples import ros_env
from bag_samples import sample_messages
import domain_coordinator
from hand_codesign.bag.reader import BagError
from hand_codesign.bag.reader import read_run
from hand_codesign.core.contract import RECORDER_READY
from hand_codesign.ros import topics
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
import numpy as np
import pytest
from rosbags.highlevel import AnyReader

pytestmark = pytest.mark.system

TEST_DIR = pathlib.Path(__file__).resolve().parent
ROOT = TEST_DIR.parents[1]
HELPERS = ROOT / 'test' / 'helpers'
# 5 generations of 60: far more than a default history depth of 10 on each topic
SAMPLE = {'generations': 5, 'population': 60, 'worlds': 2}
# Domains 200 to 232, reserved through domain_coordinator: other tests of the project use
# lower ones, and a run of another developer on the same domain would mix into the bag.
FIRST_DOMAIN = 200
LAST_DOMAIN = 232

PUBLISHER = textwrap.dedent('''
    """Publish the sample run on the loop topics, wait until the recorder has it all, exit."""
    import sys
    import time

    test_dir, sample, recorder_name = sys.argv[1:4]
    sys.path.insert(0, test_dir)
    from bag_samples import interleaved, sample_messages
    from hand_codesign.ros import topics
    import rclpy
    from rclpy.duration import Duration

    rclpy.init()
    node = rclpy.create_node('sample_publisher')
    publishers = {name: node.create_publisher(message_type, name, topics.QOS[name])
                  for name, message_type in topics.MESSAGE_TYPES.items()}
    deadline = time.monotonic() + 30.0

    def recorder_matched(topic):
        return any(info.node_name == recorder_name
                   for info in node.get_subscriptions_info_by_topic('/' + topic))

    # the graph knows the recorder before its readers match our writers: wait for both
    while not all(recorder_matched(topic) and publisher.get_subscription_count() > 0
                  for topic, publisher in publishers.items()):
        if time.monotonic() > deadline:
            sys.exit('the recorder never matched')
        time.sleep(0.02)
    messages = sample_messages(**eval(sample))
    for topic, message in interleaved(messages):
        publishers[topic].publish(message)
    for publisher in publishers.values():
        if not publisher.wait_for_all_acked(Duration(seconds=20.0)):
            sys.exit('the recorder did not acknowledge every message')
    print('published', sum(len(values) for values in messages.values()), flush=True)
    node.destroy_node()
    rclpy.shutdown()
''')


class DomainSelector:
    """Offer domain_coordinator the domains 200 to 232, from a random one on."""

    def __init__(self):
        self.next = random.randrange(FIRST_DOMAIN, LAST_DOMAIN + 1)

    def __call__(self):
        domain = self.next
        self.next = domain + 1 if domain < LAST_DOMAIN else FIRST_DOMAIN
        return domain


@pytest.fixture
def ros_domain():
    with domain_coordinator.domain_id(selector=DomainSelector()) as domain_id:
        yield ros_env(domain_id)


@pytest.fixture
def run():
    """Return the sample run of this test: its own run id and recorder name."""
    tag = uuid.uuid4().hex[:8]
    return {'sample': dict(SAMPLE, run_id=f'run-{tag}'), 'recorder': f'recorder_{tag}'}


def start_recorder(env, run, bag, *parameters):
    args = [sys.executable, '-m', 'hand_codesign.ros.recorder_node', '--ros-args',
            '-r', f'__node:={run["recorder"]}', '-p', f'bag_path:={bag}']
    for parameter in parameters:
        args += ['-p', parameter]
    return Process(args, env, cwd=ROOT)


def publish_sample(env, run, tmp_path):
    script = tmp_path / 'publisher.py'
    script.write_text(PUBLISHER)
    publisher = Process([sys.executable, str(script), str(HELPERS), repr(run['sample']),
                         run['recorder']], env, cwd=ROOT)
    try:
        assert publisher.wait(timeout=90) == 0, publisher.output
    finally:
        publisher.stop()
    return publisher.output


def assert_run_complete(record, run):
    """Check that the bag holds every message of the sample run, each once."""
    sent = sample_messages(**run['sample'])
    assert record.run_id == run['sample']['run_id']
    assert len(record.candidates) == len(sent[topics.CANDIDATES])
    assert len(record.evaluations) == len(sent[topics.EVALUATIONS])
    assert len(record.generation_summaries) == len(sent[topics.GENERATION_SUMMARY])
    own_statuses = [evaluator.startswith(record.run_id)
                    for evaluator in record.evaluator_status['evaluator_id']]
    assert sum(own_statuses) == len(sent[topics.EVALUATOR_STATUS])
    candidate_ids = record.candidates['candidate_id']
    np.testing.assert_array_equal(np.sort(candidate_ids), np.arange(len(candidate_ids)))
    np.testing.assert_array_equal(
        record.evaluations['fitness'][record.evaluations['status'] == 0],
        [m.fitness for m in sent[topics.EVALUATIONS] if m.status == 0])
    assert record.run_info.task_yaml == sent[topics.RUN_INFO][0].task_yaml


def assert_readers_decode_everything(bag):
    with open(bag, 'rb') as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        assert summary is not None and reader.get_header().profile == 'ros2'
        count = summary.statistics.message_count
        assert sum(1 for _ in reader.iter_decoded_messages()) == count
    with AnyReader([bag]) as reader:
        values = [reader.deserialize(raw, connection.msgtype)
                  for connection, _, raw in reader.messages()]
    assert len(values) == count


@pytest.mark.timeout(180)
@pytest.mark.parametrize('stop_signal', [signal.SIGINT, signal.SIGTERM])
def test_every_message_is_recorded_and_the_bag_closed_on_signal(
        ros_domain, run, tmp_path, stop_signal):
    bag = tmp_path / 'run.mcap'
    recorder = start_recorder(ros_domain, run, bag)
    try:
        assert recorder.wait_for_line(RECORDER_READY, timeout=60), recorder.output
        publish_sample(ros_domain, run, tmp_path)
        # at once: what the recorder has acknowledged must be in the bag
        recorder.popen.send_signal(stop_signal)
        assert recorder.wait(timeout=60) == 0, recorder.output
    finally:
        recorder.stop()
    assert 'Traceback' not in recorder.output and 'closed' in recorder.output
    record = read_run(bag, run_id=run['sample']['run_id'])
    assert not record.truncated, record.warning
    assert_run_complete(record, run)
    assert_readers_decode_everything(bag)


def wait_until_flushed(bag, run, timeout=60.0):
    """Wait until the bag file on disk holds every message of the sample run."""
    expected = sum(len(values) for values in sample_messages(**run['sample']).values())
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            if sum(read_run(bag, run_id=run['sample']['run_id']).message_counts.values()) \
                    >= expected:
                return
        except BagError:
            pass    # nothing flushed yet
        time.sleep(0.1)
    raise AssertionError(f'{bag} did not hold the {expected} messages in {timeout} s')


@pytest.mark.timeout(180)
def test_killed_recorder_leaves_every_flushed_message(ros_domain, run, tmp_path):
    bag = tmp_path / 'killed.mcap'
    recorder = start_recorder(ros_domain, run, bag, 'flush_period:=0.2')
    try:
        assert recorder.wait_for_line(RECORDER_READY, timeout=60), recorder.output
        publish_sample(ros_domain, run, tmp_path)
        wait_until_flushed(bag, run)
        recorder.popen.send_signal(signal.SIGKILL)
        recorder.wait(timeout=30)
    finally:
        recorder.stop()
    record = read_run(bag, run_id=run['sample']['run_id'])
    assert record.truncated and 'truncated' in record.warning
    assert_run_complete(record, run)


@pytest.mark.timeout(120)
def test_bad_parameters_give_a_clear_error(ros_domain, tmp_path):
    taken = tmp_path / 'taken.mcap'
    taken.write_bytes(b'keep me')
    for parameters, message in (((f'bag_path:={taken}',), 'taken.mcap'),
                                (('topics:=[candidates, nope]',), "['nope']")):
        recorder = Process([sys.executable, '-m', 'hand_codesign.ros.recorder_node',
                            '--ros-args'] + [arg for p in parameters for arg in ('-p', p)],
                           ros_domain, cwd=tmp_path)
        try:
            assert recorder.wait(timeout=60) == 2, recorder.output
        finally:
            recorder.stop()
        assert message in recorder.output and 'Traceback' not in recorder.output
    assert taken.read_bytes() == b'keep me'
