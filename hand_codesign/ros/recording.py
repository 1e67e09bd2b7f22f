"""
What the recorder node needs besides ROS callbacks: its parameters' checks, its QoS, its bag.

The recorder subscribes with the QoS of the publishers (reliable, transient-local where they
offer it) and a keep-all history, so that nothing the optimizer or the evaluators published is
dropped at the recorder.
"""

import datetime
import pathlib

from hand_codesign.bag.writer import BagWriteError
from hand_codesign.bag.writer import BagWriter
from hand_codesign.bag.writer import DefinitionError
from hand_codesign.bag.writer import message_definition
from hand_codesign.ros import topics
from rclpy.qos import HistoryPolicy
from rclpy.qos import QoSProfile

# name: (default, description, (lowest, highest) or None), for ros.parameters
PARAMETERS = {
    'bag_path': ('', 'Bag to write: a path ending in .mcap is one MCAP file, any other path a '
                     'rosbag2 bag directory (with metadata.yaml). Must not hold a bag yet (a '
                     "folder with other files, e.g. a run's logs/, is fine). Empty: "
                     'hand_codesign_<date>-<time>.mcap in the working directory.', None),
    'topics': (list(topics.RECORDED_MESSAGE_TYPES), 'Relative names of the topics to record; '
               'each must be a topic of the co-design loop or its view '
               '(hand_codesign.ros.topics).', None),
    'flush_period': (1.0, 'Seconds between flushes of the chunk in progress to disk: at most '
                          'this much is lost if the recorder is killed with SIGKILL.', None),
    'continue_bag': (False, 'Continue the bag directory bag_path of a recorder that died: '
                            'close its files (bag.recovery), write the next file and skip '
                            'the messages the bag already holds.', None),
}


class RecorderError(RuntimeError):
    """A recorder that cannot start: bad parameters or a bag that cannot be created."""


def recorder_qos(publisher_qos):
    """Return the subscription QoS that matches publishers offering publisher_qos, losslessly."""
    return QoSProfile(
        history=HistoryPolicy.KEEP_ALL,
        depth=publisher_qos.depth,
        reliability=publisher_qos.reliability,
        durability=publisher_qos.durability,
    )


def default_bag_path():
    """Return 'hand_codesign_<local date and time>.mcap' in the working directory."""
    return datetime.datetime.now().strftime('hand_codesign_%Y_%m_%d-%H_%M_%S.mcap')


def open_bag(settings):
    """
    Check the recorder's parameters and return a new BagWriter; raise RecorderError.

    With continue_bag the writer writes the next file of the bag directory and skips the
    messages its earlier files hold.
    """
    unknown = [name for name in settings['topics'] if name not in topics.RECORDED_MESSAGE_TYPES]
    if unknown:
        raise RecorderError(
            f'parameter topics: {unknown} are not topics of the co-design loop; expected '
            f'names among {list(topics.RECORDED_MESSAGE_TYPES)}')
    if settings['flush_period'] <= 0.0:
        raise RecorderError(
            f'parameter flush_period: expected a positive number of seconds, got '
            f'{settings["flush_period"]}')
    for name in settings['topics']:
        try:
            message_definition(topics.type_name(topics.RECORDED_MESSAGE_TYPES[name]))
        except DefinitionError as error:
            raise RecorderError(f'topic {name}: {error}') from None
    file_index, recorded, channels = 0, set(), []
    if settings['continue_bag']:
        path = pathlib.Path(settings['bag_path'])
        if not path.is_dir() or path.suffix == '.mcap':
            raise RecorderError(f'parameter continue_bag: bag_path {path} is not an existing '
                                'bag directory')
        # imported here: only a restarted recorder reads its bag (mcap's readers, ~50 ms)
        from hand_codesign.bag.files import BagError
        from hand_codesign.bag.recovery import continue_bag
        try:
            file_index, recorded, channels = continue_bag(path)
        except BagError as error:
            raise RecorderError(f'parameter continue_bag: {error}') from None
    try:
        writer = BagWriter(settings['bag_path'] or default_bag_path(), file_index=file_index,
                           skip=recorded)
        for topic, type_name, offered_qos in channels:
            writer.add_topic(topic, type_name, offered_qos)
        return writer
    except (BagWriteError, DefinitionError) as error:
        raise RecorderError(f'parameter bag_path: {error}') from None
