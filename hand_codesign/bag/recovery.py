"""
Bags that outlive their recorder: recover a cut-off MCAP file, continue a bag in a next file.

A recorder killed with SIGKILL leaves its file without the chunk in progress, summary and
footer (everything flushed before the kill is there), and its bag folder without
metadata.yaml; rosbags and Foxglove refuse such a bag. `recover_file` rewrites the complete
records of such a file into a closed, indexed file (schemas, channels and messages in their
order, then a summary and a footer) and `write_metadata` (bag.metadata) writes the folder's
metadata.yaml from the summaries of all its files: that is `hand-codesign recover BAG`.

A recorder restarted by the runner continues the same bag folder (`continue_bag`): it first
recovers the files there, then writes the next one (`<name>_1.mcap`, `<name>_2.mcap`, ...).
Filling the gap: every topic of the loop except the heartbeats is transient-local with a deep
history (ros.topics.HISTORY_DEPTH per publisher), so the new recorder receives again the latest
messages of every publisher still alive, those of the gap and those the killed recorder had not
flushed yet among them. It skips every message whose topic and bytes are already in the bag's
earlier files (`recorded_messages`): each message of the run is in the bag once. No two
messages of a run are equal byte for byte (a candidate carries its id and attempt, an
evaluation those and its evaluator, a summary its generation, a heartbeat its stamp). The files
are read as a stream (a recovery needs no memory beyond a chunk); the keys of the messages take
about 100 bytes each, 20 MB for a run of 100,000 evaluations. What cannot come back: heartbeats
of the gap (volatile; only their latest value matters), messages of a publisher that exited
during the gap, and anything beyond the history depth of one publisher between the killed
recorder's last flush and the new one's start.

No rclpy here: `hand-codesign recover` works on a machine without ROS.
"""

import os
import pathlib

from hand_codesign.bag.files import bag_files
from hand_codesign.bag.files import BagRecoveryError
from hand_codesign.bag.files import check_start
from hand_codesign.bag.files import MCAP_MAGIC
from hand_codesign.bag.files import Records
from hand_codesign.bag.metadata import add_rosbag2_record
from hand_codesign.bag.metadata import file_information
from hand_codesign.bag.metadata import topic_information
from hand_codesign.bag.metadata import write_metadata
from hand_codesign.bag.writer import LIBRARY
from hand_codesign.bag.writer import message_key
from hand_codesign.bag.writer import PROFILE
from mcap.records import Channel
from mcap.records import Header
from mcap.records import Message
from mcap.records import Schema
from mcap.writer import CompressionType
from mcap.writer import Writer


def records(path):
    """
    Yield the records of one MCAP file front to back, stopping quietly where it is cut off.

    A file cut off before its header (even an empty one) yields nothing. Raise BagError
    (bag.files) for a file that does not start as an MCAP file.
    """
    check_start(path, cut_ok=True)
    yield from Records(path)


def is_closed(path):
    """Return whether an MCAP file ends as a closed one does: footer, then the magic bytes."""
    with open(path, 'rb') as stream:
        stream.seek(0, os.SEEK_END)
        if stream.tell() < 2 * len(MCAP_MAGIC):
            return False
        stream.seek(-len(MCAP_MAGIC), os.SEEK_END)
        return stream.read() == MCAP_MAGIC


def recover_file(path):
    """Close a cut-off MCAP file in place; return the messages kept, or None if it was closed."""
    path = pathlib.Path(path)
    if is_closed(path):
        return None
    partial = path.with_name(path.name + '.recovering')
    try:
        kept = _rewrite(path, partial)
    except BaseException:
        partial.unlink(missing_ok=True)
        raise
    os.replace(partial, path)
    return kept


def _rewrite(path, partial):
    """Write the complete records of the cut-off file path, closed, to partial."""
    kept = 0
    with open(partial, 'wb') as stream:
        writer = Writer(stream, compression=CompressionType.ZSTD)
        # the ids stay those of the cut-off file (ours count from 1 as mcap's Writer does),
        # so that they stay those of the other files of the bag
        schema_ids, channel_ids, started = {}, {}, False
        # what the rosbag2 record of the file says: its channels, their counts, its times
        schema_names, channels, counts, times = {}, {}, {}, [None, None]
        for record in records(path):
            kind = type(record)
            if kind is Header:
                writer.start(profile=record.profile or PROFILE,
                             library=record.library or LIBRARY)
                started = True
            elif kind is Schema and record.id not in schema_ids:
                schema_ids[record.id] = writer.register_schema(
                    record.name, record.encoding, record.data)
                schema_names[record.id] = record.name
            elif kind is Channel and record.id not in channel_ids:
                channel_ids[record.id] = writer.register_channel(
                    record.topic, record.message_encoding,
                    schema_ids.get(record.schema_id, 0), dict(record.metadata))
                channels[record.id] = record
            elif kind is Message and record.channel_id in channel_ids:
                writer.add_message(channel_ids[record.channel_id], record.log_time,
                                   record.data, record.publish_time, record.sequence)
                counts[record.channel_id] = counts.get(record.channel_id, 0) + 1
                times = [min(times[0] or record.log_time, record.log_time),
                         max(times[1] or record.log_time, record.log_time)]
                kept += 1
        if not started:     # cut off before its header: an empty bag file
            writer.start(profile=PROFILE, library=LIBRARY)
        # as the recorder would have on close (a cut-off file never holds this record)
        add_rosbag2_record(writer, [
            topic_information(channel.topic, schema_names.get(channel.schema_id, ''),
                              channel.metadata.get('offered_qos_profiles'),
                              channel.metadata.get('topic_type_hash', ''),
                              counts.get(channel_id, 0))
            for channel_id, channel in channels.items()],
            file_information(path.name, times[0] or 0, times[1] or 0, kept))
        writer.finish()
        stream.flush()
        os.fsync(stream.fileno())
    return kept


def recorded_messages(files):
    """
    Return what the given MCAP files hold: (message keys, channels).

    The keys are the message_key of every message; the channels are (topic, schema name,
    offered QoS text) by channel id, in id order.
    """
    keys, channels_by_id = set(), {}
    for path in files:
        schemas, topics = {}, {}
        for record in records(path):
            kind = type(record)
            if kind is Message:
                keys.add(message_key(topics.get(record.channel_id, ''), record.data))
            elif kind is Schema:
                schemas[record.id] = record.name
            elif kind is Channel:
                topics[record.id] = record.topic
                channels_by_id.setdefault(record.id, (
                    record.topic, schemas.get(record.schema_id, ''),
                    record.metadata.get('offered_qos_profiles', '')))
    return keys, [channels_by_id[channel_id] for channel_id in sorted(channels_by_id)]


def continue_bag(folder):
    """
    Recover the files of a bag folder; return (next file index, message keys, channels).

    A continued file must declare the channels of the earlier ones first, in their order:
    readers of a split bag (rosbags) take a channel id to mean one topic in every file.
    """
    files = bag_files(folder)
    for path in files:
        recover_file(path)
    keys, channels = recorded_messages(files)
    return len(files), keys, channels


def recover_bag(path):
    """Recover a bag (folder or .mcap file); return [(file, messages kept or None if closed)]."""
    path = pathlib.Path(path)
    if not path.exists():
        raise BagRecoveryError(f'{path}: no such file or directory; expected a bag folder or '
                               'a .mcap file written by the hand_codesign recorder')
    files = [path] if path.is_file() else bag_files(path)
    if not files:
        raise BagRecoveryError(f'{path}: a folder without .mcap files; expected a bag folder '
                               'written by the hand_codesign recorder')
    report = [(file, recover_file(file)) for file in files]
    if path.is_dir():
        write_metadata(path)
    return report
