"""
A bag folder's rosbag2 metadata: the records rosbag2 keeps beside and inside the MCAP files.

The vocabulary both the bag writer (bag.writer) and the bag mender (bag.recovery) build on,
so that neither needs the other's module: rosbag2's TopicInformation, FileInformation and
BagMetadata (Jazzy, version 9), the metadata record inside each MCAP file, and
`write_metadata`, which writes a folder's metadata.yaml from the summaries of all its files
(in the order of bag.files.bag_files).
"""

import pathlib

from hand_codesign.bag.files import bag_files
from hand_codesign.bag.files import BagRecoveryError
from mcap.reader import make_reader
import yaml

MESSAGE_ENCODING = 'cdr'
# rosbag2 reads a directory's metadata.yaml of version 9 (Jazzy) with QoS enums as names.
METADATA_VERSION = 9
# rosbag2's MCAP storage plugin keeps the bag's metadata in a metadata record of this name
ROSBAG2_RECORD, ROSBAG2_RECORD_KEY = 'rosbag2', 'serialized_metadata'


def topic_information(topic, type_name, offered_qos_profiles, type_description_hash, count):
    """Return rosbag2's TopicInformation of a topic (version 9: QoS profiles as a list)."""
    return {'topic_metadata': {
        'name': topic, 'type': type_name, 'serialization_format': MESSAGE_ENCODING,
        'offered_qos_profiles': yaml.safe_load(offered_qos_profiles or '[]') or [],
        'type_description_hash': type_description_hash},
        'message_count': count}


def file_information(name, start, end, count):
    """Return rosbag2's FileInformation of one file (times in ns since the epoch)."""
    return {'path': name, 'starting_time': {'nanoseconds_since_epoch': start if count else 0},
            'duration': {'nanoseconds': end - start if count else 0}, 'message_count': count}


def bag_metadata(topics, files):
    """
    Return rosbag2's BagMetadata (Jazzy, version 9) of TopicInformation and FileInformation.

    The same record is metadata.yaml's `rosbag2_bagfile_information` and, serialized, the
    `serialized_metadata` of the "rosbag2" metadata record inside each MCAP file (ROSBAG2_RECORD).
    """
    counted = [entry for entry in files if entry['message_count']]
    start = min((entry['starting_time']['nanoseconds_since_epoch'] for entry in counted),
                default=0)
    end = max((entry['starting_time']['nanoseconds_since_epoch']
               + entry['duration']['nanoseconds'] for entry in counted), default=0)
    return {
        'version': METADATA_VERSION,
        'storage_identifier': 'mcap',
        'duration': {'nanoseconds': end - start},
        'starting_time': {'nanoseconds_since_epoch': start},
        'message_count': sum(entry['message_count'] for entry in topics),
        'topics_with_message_count': list(topics),
        'compression_format': '',
        'compression_mode': '',
        'relative_file_paths': [entry['path'] for entry in files],
        'files': list(files),
        'custom_data': {},
        'ros_distro': 'jazzy',
    }


def add_rosbag2_record(writer, topics, file):
    """
    Add the metadata record rosbag2's MCAP storage writes when it closes a file.

    `ros2 bag info file.mcap` reads it (version, QoS format, distribution); without it rosbag2
    falls back to defaults. topics: TopicInformation of the file; file: its FileInformation.
    """
    text = yaml.safe_dump(bag_metadata(topics, [file]), sort_keys=False,
                          default_flow_style=False)
    writer.add_metadata(ROSBAG2_RECORD, {ROSBAG2_RECORD_KEY: text})


def _file_summary(path):
    """Return (channels, schema names, counts by channel id, start, end) of a closed file."""
    with open(path, 'rb') as stream:
        summary = make_reader(stream).get_summary()
    if summary is None or summary.statistics is None:
        raise BagRecoveryError(f'{path}: no summary; recover the bag first')
    statistics = summary.statistics
    names = {schema_id: schema.name for schema_id, schema in summary.schemas.items()}
    return (summary.channels, names, statistics.channel_message_counts,
            statistics.message_start_time, statistics.message_end_time,
            statistics.message_count)


def write_metadata(folder):
    """Write the rosbag2 metadata.yaml of a bag folder from the summaries of all its files."""
    folder = pathlib.Path(folder)
    topics, files = {}, []
    for path in bag_files(folder):
        channels, names, counts, start, end, count = _file_summary(path)
        for channel_id, channel in channels.items():
            entry = topics.setdefault(channel.topic, topic_information(
                channel.topic, names.get(channel.schema_id, ''),
                channel.metadata.get('offered_qos_profiles'),
                channel.metadata.get('topic_type_hash', ''), 0))
            entry['message_count'] += counts.get(channel_id, 0)
        files.append(file_information(path.name, start, end, count))
    metadata = {'rosbag2_bagfile_information': bag_metadata(list(topics.values()), files)}
    (folder / 'metadata.yaml').write_text(
        yaml.safe_dump(metadata, sort_keys=False, default_flow_style=False), encoding='utf-8')
