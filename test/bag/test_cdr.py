"""The schema-compiled CDR decoders give what rclpy itself deserializes, for every field kind."""

from bag_samples import sample_messages
from diagnostic_msgs.msg import DiagnosticArray
from diagnostic_msgs.msg import DiagnosticStatus
from diagnostic_msgs.msg import KeyValue
from geometry_msgs.msg import PoseWithCovarianceStamped
from hand_codesign.bag import cdr
from hand_codesign.bag.writer import message_definition
from hand_codesign.ros import topics
import numpy as np
import pytest
from rclpy.serialization import serialize_message
from sensor_msgs.msg import JointState


def decoder_for(message_class):
    type_name = topics.type_name(message_class)
    return cdr.compile_schema(type_name, message_definition(type_name))


def as_plain(message):
    """Return an rclpy message as the decoders give it: a tuple, times in ns, lists as tuples."""
    if hasattr(message, 'sec') and hasattr(message, 'nanosec'):
        return message.sec * 1_000_000_000 + message.nanosec
    if not hasattr(message, 'get_fields_and_field_types'):
        return message
    values = []
    for name in message.get_fields_and_field_types():
        value = getattr(message, name)
        if isinstance(value, (list, tuple)) and value and isinstance(value[0], str):
            values.append(tuple(value))
        elif isinstance(value, list):
            values.append([as_plain(item) for item in value])
        elif hasattr(value, '__len__') and not isinstance(value, str):
            values.append(np.asarray(value))
        else:
            values.append(as_plain(value))
    return tuple(values)


def assert_equal(actual, expected):
    if isinstance(expected, np.ndarray):
        assert isinstance(actual, np.ndarray)
        np.testing.assert_array_equal(actual, expected)
    elif isinstance(expected, (tuple, list)):
        assert len(actual) == len(expected)
        for actual_item, expected_item in zip(actual, expected):
            assert_equal(actual_item, expected_item)
    else:
        assert actual == expected
        assert type(actual) is type(expected) or isinstance(expected, (int, float))


@pytest.mark.parametrize('topic', list(topics.MESSAGE_TYPES))
def test_loop_messages_decode_like_rclpy(topic):
    decode = decoder_for(topics.MESSAGE_TYPES[topic])
    messages = sample_messages()[topic]
    assert messages
    # twice: the second pass goes through the reuse of repeated name lists
    for message in messages + messages[::-1]:
        assert_equal(decode(serialize_message(message)), as_plain(message))


def test_standard_types_with_fixed_arrays_nested_sequences_and_bare_names():
    pose = PoseWithCovarianceStamped()
    pose.header.frame_id = 'palm'
    pose.header.stamp.sec, pose.header.stamp.nanosec = 12, 345
    pose.pose.pose.position.x = 1.5
    pose.pose.pose.orientation.w = -0.25
    pose.pose.covariance = np.arange(36, dtype=float)
    joints = JointState(name=['a', 'bb', 'ccc'], position=[0.1, 0.2, 0.3], velocity=[],
                        effort=[1.0])
    array = DiagnosticArray(status=[
        DiagnosticStatus(level=b'\x02', name='n1', message='m',
                         values=[KeyValue(key='k', value='v'), KeyValue(key='k2', value='')]),
        DiagnosticStatus(level=b'\x00', name='', message='', values=[]),
    ])
    for message in (pose, joints, array, JointState()):
        decode = decoder_for(type(message))
        decoded = decode(serialize_message(message))
        if isinstance(message, DiagnosticArray):
            header, statuses = decoded
            assert [(status[0], status[1], status[4]) for status in statuses] == [
                (2, 'n1', [('k', 'v'), ('k2', '')]), (0, '', [])]
        else:
            assert_equal(decoded, as_plain(message))


def test_message_that_ends_early_raises():
    decode = decoder_for(topics.MESSAGE_TYPES[topics.CANDIDATES])
    data = serialize_message(sample_messages()[topics.CANDIDATES][0])
    with pytest.raises(ValueError):
        decode(data[:len(data) // 2])


def test_big_endian_and_unknown_definitions_are_left_to_a_generic_decoder():
    decode = decoder_for(topics.MESSAGE_TYPES[topics.RUN_INFO])
    with pytest.raises(cdr.UnsupportedSchema):
        decode(b'\x00\x00\x00\x00' + bytes(64))
    with pytest.raises(cdr.UnsupportedSchema, match='no definition'):
        cdr.compile_schema('pkg/msg/Thing', 'other_pkg/Missing field\n')
    with pytest.raises(cdr.UnsupportedSchema, match='wstring'):
        cdr.compile_schema('pkg/msg/Thing', 'wstring text\n')
