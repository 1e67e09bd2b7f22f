"""The MCAP writer writes bags that rosbag2-aware readers (mcap-ros2-support, rosbags) read."""

import pathlib

from ament_index_python.packages import get_package_share_directory
from bag_samples import interleaved
from bag_samples import rosbag2_record
from bag_samples import sample_messages
from bag_samples import write_bag
from hand_codesign.bag.writer import BagWriteError
from hand_codesign.bag.writer import BagWriter
from hand_codesign.bag.writer import DefinitionError
from hand_codesign.bag.writer import message_definition
from hand_codesign.ros import topics
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
import numpy as np
import pytest
from rosbags.highlevel import AnyReader
from rosbags.rosbag2 import Reader as Rosbag2Reader
import yaml

DELIMITER = '=' * 80


def msg_text(package, name):
    return (pathlib.Path(get_package_share_directory(package)) / 'msg' / f'{name}.msg').read_text()


def assert_same_message(decoded, original):
    """Compare a decoded message (any reader) with the rclpy message field by field."""
    for name in original.get_fields_and_field_types():
        expected = getattr(original, name)
        actual = getattr(decoded, name)
        if name == 'stamp':
            assert (actual.sec, actual.nanosec) == (expected.sec, expected.nanosec)
        elif hasattr(expected, 'get_fields_and_field_types'):   # a nested message
            assert_same_message(actual, expected)
        elif isinstance(expected, (str, bool, int, float)):
            assert actual == expected, name
        else:
            assert list(actual) == list(expected), name


def test_schema_of_a_type_with_a_dependency_is_laid_out_as_rosbag2_does():
    text = message_definition('hand_codesign_msgs/msg/RunInfo')
    expected = (msg_text('hand_codesign_msgs', 'RunInfo') + '\n' + DELIMITER + '\n'
                + 'MSG: builtin_interfaces/Time\n' + msg_text('builtin_interfaces', 'Time'))
    assert text == expected
    # a type without dependencies is its own text, nothing appended
    assert message_definition('hand_codesign_msgs/msg/Candidate') == msg_text(
        'hand_codesign_msgs', 'Candidate')


def test_dependencies_are_depth_first_each_once_with_bare_names_prefixed():
    text = message_definition('geometry_msgs/msg/PoseWithCovarianceStamped')
    headers = [line for line in text.splitlines() if line.startswith('MSG: ')]
    # Header and PoseWithCovariance as written in the fields; Pose's bare "Point" prefixed.
    assert headers == ['MSG: geometry_msgs/PoseWithCovariance', 'MSG: geometry_msgs/Pose',
                       'MSG: geometry_msgs/Point', 'MSG: geometry_msgs/Quaternion',
                       'MSG: std_msgs/Header', 'MSG: builtin_interfaces/Time']
    assert text.count(DELIMITER) == len(headers)


def test_unknown_type_names_its_package():
    with pytest.raises(DefinitionError, match='no_such_msgs'):
        message_definition('no_such_msgs/msg/Thing')
    with pytest.raises(DefinitionError, match='not of the form'):
        message_definition('Thing')


def test_bag_file_reads_back_with_mcap_ros2_support_and_rosbags(tmp_path):
    messages = sample_messages()
    path = tmp_path / 'run.mcap'
    write_bag(path, messages)
    expected = interleaved(messages)

    with open(path, 'rb') as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        header = reader.get_header()
        summary = reader.get_summary()
        assert header.profile == 'ros2'
        assert summary.statistics.message_count == len(expected)
        assert {chunk.compression for chunk in summary.chunk_indexes} == {'zstd'}
        for schema in summary.schemas.values():
            assert schema.encoding == 'ros2msg'
            assert schema.data.decode() == message_definition(schema.name)
        for channel in summary.channels.values():
            assert channel.message_encoding == 'cdr'
            qos = yaml.safe_load(channel.metadata['offered_qos_profiles'])
            declared = topics.QOS[channel.topic.lstrip('/')]
            assert qos[0]['reliability'] == declared.reliability.name.lower()
            assert qos[0]['durability'] == declared.durability.name.lower()
            assert qos[0]['depth'] == declared.depth
            assert channel.metadata['topic_type_hash'].startswith('RIHS01_')
        decoded = [(channel.topic, message, ros_message)
                   for _, channel, message, ros_message in reader.iter_decoded_messages()]
    assert len(decoded) == len(expected)
    for (topic, message, ros_message), (expected_topic, original) in zip(decoded, expected):
        assert topic == '/' + expected_topic
        assert message.log_time == message.publish_time
        assert_same_message(ros_message, original)

    with AnyReader([path]) as reader:
        read = [(connection.topic, reader.deserialize(raw, connection.msgtype))
                for connection, _, raw in reader.messages()]
        assert {connection.topic: connection.ext.offered_qos_profiles[0].depth
                for connection in reader.connections} == {
                    '/' + topic: topics.QOS[topic].depth for topic in messages}
    assert len(read) == len(expected)
    for (topic, message), (expected_topic, original) in zip(read, expected):
        assert topic == '/' + expected_topic
        assert_same_message(message, original)


def test_a_bare_file_holds_the_rosbag2_metadata_record_ros2_bag_info_reads(tmp_path):
    messages = sample_messages()
    path = tmp_path / 'run.mcap'
    write_bag(path, messages)
    metadata = rosbag2_record(path)
    with open(path, 'rb') as stream:
        summary = make_reader(stream).get_summary()
    statistics = summary.statistics
    assert metadata['version'] == 9 and metadata['ros_distro'] == 'jazzy'
    assert metadata['storage_identifier'] == 'mcap' and metadata['compression_mode'] == ''
    assert metadata['relative_file_paths'] == ['run.mcap']
    assert metadata['message_count'] == statistics.message_count
    assert metadata['starting_time'] == {'nanoseconds_since_epoch': statistics.message_start_time}
    assert metadata['duration'] == {
        'nanoseconds': statistics.message_end_time - statistics.message_start_time}
    assert metadata['files'] == [{
        'path': 'run.mcap', 'starting_time': metadata['starting_time'],
        'duration': metadata['duration'], 'message_count': statistics.message_count}]
    channels = {channel.topic: channel for channel in summary.channels.values()}
    assert len(metadata['topics_with_message_count']) == len(channels)
    for entry in metadata['topics_with_message_count']:
        topic = entry['topic_metadata']
        channel = channels[topic['name']]
        assert entry['message_count'] == statistics.channel_message_counts[channel.id]
        assert topic['type'] == summary.schemas[channel.schema_id].name
        assert topic['serialization_format'] == 'cdr'
        # version 9: the QoS profiles as a YAML list, the same as the channel's own
        assert topic['offered_qos_profiles'] == yaml.safe_load(
            channel.metadata['offered_qos_profiles'])
        assert topic['type_description_hash'] == channel.metadata['topic_type_hash']


def test_bag_directory_has_rosbag2_metadata_and_reads_with_rosbags(tmp_path):
    messages = sample_messages(generations=1)
    bag = tmp_path / 'run_bag'
    writer = write_bag(bag, messages)
    assert writer.file_path == bag / 'run_bag_0.mcap'
    metadata = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert metadata['storage_identifier'] == 'mcap'
    assert metadata['relative_file_paths'] == ['run_bag_0.mcap']
    counts = {entry['topic_metadata']['name']: entry['message_count']
              for entry in metadata['topics_with_message_count']}
    assert counts == {'/' + topic: len(values) for topic, values in messages.items()}
    with Rosbag2Reader(bag) as reader:
        assert reader.message_count == sum(counts.values())
        assert {c.topic: c.msgcount for c in reader.connections} == counts
    with AnyReader([bag]) as reader:
        values = [reader.deserialize(raw, connection.msgtype)
                  for connection, _, raw in reader.messages()]
    assert len(values) == sum(counts.values())


def test_flush_writes_complete_chunks_before_close(tmp_path):
    messages = sample_messages(generations=1)
    path = tmp_path / 'open.mcap'
    writer = write_bag(path, messages, flush_every=10, close=False)
    writer.flush()
    assert writer.unflushed_count == 0
    size = path.stat().st_size
    assert size > 0
    writer.close()
    assert path.stat().st_size > size
    with pytest.raises(BagWriteError, match='closed'):
        writer.write('/candidates', b'\x00\x01\x00\x00')
    writer.close()   # idempotent


def test_existing_bag_is_never_overwritten(tmp_path):
    path = tmp_path / 'taken.mcap'
    path.write_bytes(b'precious')
    with pytest.raises(BagWriteError, match='taken.mcap'):
        BagWriter(path)
    assert path.read_bytes() == b'precious'
    with pytest.raises(BagWriteError, match='no channel'):
        with BagWriter(tmp_path / 'other.mcap') as writer:
            writer.write('/nowhere', b'')


def test_bag_directory_may_hold_other_files_but_never_a_bag(tmp_path):
    bag = tmp_path / 'run'
    (bag / 'logs').mkdir(parents=True)   # `hand-codesign run` creates it before the recorder
    (bag / 'logs' / 'evaluator-0.log').write_text('started')
    write_bag(bag, sample_messages(generations=1))
    assert sorted(path.name for path in bag.iterdir()) == ['logs', 'metadata.yaml', 'run_0.mcap']
    with pytest.raises(BagWriteError, match='holds a bag already'):
        BagWriter(bag)
    (bag / 'metadata.yaml').unlink()   # a killed recorder leaves its MCAP file without it
    with pytest.raises(BagWriteError, match='holds a bag already'):
        BagWriter(bag)
    assert (bag / 'logs' / 'evaluator-0.log').read_text() == 'started'


def test_rejected_evaluation_round_trips_with_empty_arrays(tmp_path):
    messages = sample_messages(generations=1)
    rejected = [m for m in messages[topics.EVALUATIONS] if m.status == m.STATUS_REJECTED]
    path = tmp_path / 'rejected.mcap'
    write_bag(path, {topics.EVALUATIONS: rejected})
    with AnyReader([path]) as reader:
        (connection, _, raw), = list(reader.messages())
        message = reader.deserialize(raw, connection.msgtype)
    assert message.reason == 'genome has NaN — rejected'
    assert np.asarray(message.objectives).size == 0
