"""
Write rosbag2-compatible MCAP bags from serialized (CDR) messages.

The file layout is the one rosbag2's MCAP storage plugin writes, so that ``ros2 bag``,
Foxglove, mcap-ros2-support and rosbags read our bags like any recorded with ``ros2 bag``:

- profile ``ros2``; one schema per message type, named like ``pkg/msg/Type``, with encoding
  ``ros2msg`` and as data the type's own ``.msg`` text followed by every dependency (depth
  first, each once) after a line of 80 ``=`` and a line ``MSG: <type as written in the field>``;
- one channel per topic (absolute name), message encoding ``cdr``, and in its metadata the
  publishers' ``offered_qos_profiles`` (a YAML list, as rosbag2 serializes it) and the
  ``topic_type_hash`` (RIHS01) of the type;
- zstd-compressed chunks with message indexes; on close a metadata record named ``rosbag2``
  whose ``serialized_metadata`` is the YAML of the file's BagMetadata (what ``ros2 bag info``
  reads of a bare file: the metadata version, hence the QoS format, and the distribution),
  then the summary (schemas, channels, statistics, chunk and metadata indexes, summary
  offsets) and the footer.

A bag is either one ``.mcap`` file (``ros2 bag info file.mcap``, ``ros2 bag play file.mcap``,
rosbags and mcap all read a bare file) or, for a path without the ``.mcap`` suffix, a rosbag2
bag directory ``<path>/<name>_0.mcap`` with the ``metadata.yaml`` that ``ros2 bag`` and
``rosbags.rosbag2.Reader`` expect of a directory (written on close; ``ros2 bag reindex``
rebuilds it for a directory whose recorder was killed).

Message definitions are looked up at run time in ``share/<pkg>/msg/<Type>.msg`` of the
packages on ``AMENT_PREFIX_PATH`` (via ament_index_python), so any installed type works.

Records, chunks, compression and the summary are mcap's ``Writer``; what is ours is only what
rosbag2 adds and no library here writes:

- the schema text: rosbag2 stores the .msg files as they are, comments included, joined as
  above; rosbags' ``Typestore.generate_msgdef`` writes a text of its own (361 characters for
  RunInfo, against rosbag2's 1,804), so readers that compare definitions see another type.
  The dependency scan below is rosbag2's own regular expression, for the same bytes;
- the bag itself: ``rosbags.rosbag2.Writer`` takes raw CDR and a given schema text, but it
  writes only bag directories (no bare ``.mcap`` file), cannot flush the chunk in progress
  (a killed recorder loses everything since the last full 1 MiB chunk, and the chunk index
  lives in memory until close), records one time per message (no publish time) and leaves
  out the channel's ``topic_type_hash``; mcap-ros2-support's writer serializes message
  objects itself and takes no raw CDR.
"""

import hashlib
import json
import os
import pathlib
import re
import time
from typing import Any, Collection, Dict, Optional, Sequence, Tuple, Union

from ament_index_python.packages import get_package_share_directory
from ament_index_python.packages import PackageNotFoundError
from hand_codesign.bag.metadata import add_rosbag2_record
from hand_codesign.bag.metadata import file_information
from hand_codesign.bag.metadata import MESSAGE_ENCODING
from hand_codesign.bag.metadata import topic_information
from hand_codesign.bag.metadata import write_metadata
from mcap.writer import CompressionType
from mcap.writer import Writer
import yaml

PROFILE = 'ros2'
SCHEMA_ENCODING = 'ros2msg'
LIBRARY = 'hand_codesign.mcap_writer'
DEFINITION_DELIMITER = '=' * 80

# The field-type pattern and primitive list of rosbag2's local message definition source:
# keeping them identical makes our schema text byte-identical to the one rosbag2 writes.
_FIELD_TYPE = re.compile(r'(?:^|\n)\s*([a-zA-Z0-9_/]+)(?:\[[^\]]*\])?\s+')
_PRIMITIVE_TYPES = frozenset((
    'bool', 'byte', 'char', 'float32', 'float64', 'int8', 'uint8', 'int16', 'uint16',
    'int32', 'uint32', 'int64', 'uint64', 'string'))
_TYPE_NAME = re.compile(r'^([a-zA-Z][a-zA-Z0-9_]*)/(?:([a-zA-Z][a-zA-Z0-9_]*)/)?'
                        r'([a-zA-Z][a-zA-Z0-9_]*)$')
_MAX_DEFINITION_DEPTH = 50


class DefinitionError(LookupError):
    """A message type whose definition cannot be found or understood."""


class BagWriteError(RuntimeError):
    """A bag that cannot be written (bad path, unknown topic, writer already closed)."""


def _split_type_name(type_name):
    """Return (package, namespace, name) of 'pkg/msg/Type' or 'pkg/Type'."""
    match = _TYPE_NAME.match(type_name)
    if match is None:
        raise DefinitionError(
            f'message type {type_name!r} is not of the form "package/msg/Type" or '
            '"package/Type"')
    package, namespace, name = match.groups()
    return package, namespace or 'msg', name


def _interface_file(type_name, extension):
    """Return the path of the installed interface file of a type, e.g. its .msg."""
    package, namespace, name = _split_type_name(type_name)
    try:
        share = get_package_share_directory(package)
    except (PackageNotFoundError, LookupError, ValueError) as error:
        raise DefinitionError(
            f'package {package!r} of message type {type_name!r} is not installed under '
            f'AMENT_PREFIX_PATH={os.environ.get("AMENT_PREFIX_PATH", "")!r}: {error}'
        ) from None
    return pathlib.Path(share) / namespace / f'{name}{extension}'


def _msg_text(type_name):
    """Return the installed .msg text of a type exactly as on disk."""
    path = _interface_file(type_name, '.msg')
    try:
        return path.read_text(encoding='utf-8')
    except OSError as error:
        raise DefinitionError(
            f'no message definition for {type_name!r}: cannot read {path}: {error}') from None


def msg_dependencies(text, package):
    """Return the sorted non-primitive field types of a .msg text, bare names prefixed."""
    dependencies = set()
    for match in _FIELD_TYPE.finditer(text):
        field_type = match.group(1)
        if field_type in _PRIMITIVE_TYPES:
            continue
        dependencies.add(field_type if '/' in field_type else f'{package}/{field_type}')
    return sorted(dependencies)


def message_definition(type_name):
    """
    Return the complete ``ros2msg`` definition of a type as rosbag2 writes it in a schema.

    The type's own .msg text comes first; then, depth first and each once, every type it
    depends on, each preceded by a line of 80 '=' and a line 'MSG: <name as in the field>'.
    """
    seen = set()

    def append(name, depth):
        if depth > _MAX_DEFINITION_DEPTH:
            raise DefinitionError(f'definition of {type_name!r} nests deeper than '
                                  f'{_MAX_DEFINITION_DEPTH} levels')
        text = _msg_text(name)
        parts = [text]
        for dependency in msg_dependencies(text, _split_type_name(name)[0]):
            if dependency in seen:
                continue
            seen.add(dependency)
            parts.append(f'\n{DEFINITION_DELIMITER}\nMSG: {dependency}\n')
            parts.append(append(dependency, depth + 1))
        return ''.join(parts)

    return append(type_name, 0)


def type_hash(type_name):
    """Return the RIHS01 type hash of an installed type, or '' when it has none on disk."""
    path = _interface_file(type_name, '.json')
    try:
        description = json.loads(path.read_text(encoding='utf-8'))
    except (OSError, ValueError):
        return ''
    full_name = '{}/{}/{}'.format(*_split_type_name(type_name))
    for entry in description.get('type_hashes', ()):
        if entry.get('type_name') == full_name:
            return entry.get('hash_string', '')
    return ''


def message_key(topic, data):
    """Return what identifies a recorded message: its topic and a digest of its bytes."""
    return topic, hashlib.blake2b(bytes(data), digest_size=16).digest()


def _policy_name(policy):
    """Return the rmw string of a QoS policy (enum, int-like enum or already a string)."""
    if isinstance(policy, str):
        return policy.lower()
    return policy.name.lower()


def _duration(value):
    """Return {'sec', 'nsec'} of an rclpy Duration, a {'sec', 'nsec'} dict or nanoseconds."""
    if isinstance(value, dict):
        return {'sec': int(value['sec']), 'nsec': int(value['nsec'])}
    nanoseconds = int(getattr(value, 'nanoseconds', value))
    return {'sec': nanoseconds // 1_000_000_000, 'nsec': nanoseconds % 1_000_000_000}


def qos_profile_dict(profile):
    """Return one QoS profile as rosbag2 serializes it (Jazzy: policies by name)."""
    return {
        'history': _policy_name(profile.history),
        'depth': int(profile.depth),
        'reliability': _policy_name(profile.reliability),
        'durability': _policy_name(profile.durability),
        'deadline': _duration(profile.deadline),
        'lifespan': _duration(profile.lifespan),
        'liveliness': _policy_name(profile.liveliness),
        'liveliness_lease_duration': _duration(profile.liveliness_lease_duration),
        'avoid_ros_namespace_conventions': bool(profile.avoid_ros_namespace_conventions),
    }


def qos_profiles_yaml(profiles: Sequence[Any]) -> str:
    """
    Return the ``offered_qos_profiles`` text of a channel: a YAML list, '' for none.

    profiles: rclpy QoSProfile objects (or anything with the same attributes), one per
    publisher offering on the topic, as rosbag2 records them.
    """
    if not profiles:
        return ''
    dicts = [qos_profile_dict(profile) for profile in profiles]
    return yaml.safe_dump(dicts, sort_keys=False, default_flow_style=False).rstrip('\n')


def holds_bag(folder):
    """Return whether a folder holds the files of a bag (its metadata or an MCAP file)."""
    return (folder / 'metadata.yaml').exists() or any(folder.glob('*.mcap'))


class BagWriter:
    """
    Append serialized messages to a rosbag2-compatible MCAP bag.

    Not thread-safe: call it from one thread (the recorder's executor). Messages are kept in
    the current chunk in memory until it is full or ``flush()`` is called; ``close()`` writes
    the last chunk, the summary and the footer.
    """

    def __init__(self, path: Union[str, pathlib.Path], chunk_size: int = 1024 * 1024,
                 compression: str = 'zstd', file_index: int = 0,
                 skip: Collection[Tuple[str, bytes]] = ()) -> None:
        """
        Create the bag at path: 'x.mcap' is one file, any other path a bag directory.

        Args:
            path: the bag: a file ending in .mcap, or a directory (created; one that holds a
                bag already is refused).
            chunk_size: bytes of messages kept in memory before a chunk is written.
            compression: of the chunks: 'zstd', 'lz4' or 'none'.
            file_index: > 0 continues an existing bag directory with its file
                <name>_<index>.mcap (bag.recovery.continue_bag, for a restarted recorder).
            skip: message_keys of messages write() leaves out (what the earlier files hold).

        Raises:
            BagWriteError: for an unknown compression or a bag that cannot be created.
        """
        self.bag_path = pathlib.Path(path)
        if self.bag_path.suffix == '.mcap':
            self.is_directory = False
            self.file_path = self.bag_path
        else:
            self.is_directory = True
            self.file_path = self.bag_path / f'{self.bag_path.name}_{file_index}.mcap'
        compression_types = {'zstd': CompressionType.ZSTD, 'lz4': CompressionType.LZ4,
                             'none': CompressionType.NONE}
        if compression not in compression_types:
            raise BagWriteError(f'unknown chunk compression {compression!r}: expected one of '
                                f'{sorted(compression_types)}')
        try:
            if self.is_directory:
                # a folder may exist already (`run` creates it with the run's logs/ first),
                # but a bag in it is never written over
                self.bag_path.mkdir(parents=True, exist_ok=True)
                if file_index == 0 and holds_bag(self.bag_path):
                    raise FileExistsError(f'{self.bag_path} holds a bag already')
            else:
                self.file_path.parent.mkdir(parents=True, exist_ok=True)
            self._stream = open(self.file_path, 'xb')
        except OSError as error:
            raise BagWriteError(f'cannot create bag {self.bag_path}: {error}') from None
        self._writer = Writer(self._stream, chunk_size=chunk_size,
                              compression=compression_types[compression])
        self._writer.start(profile=PROFILE, library=LIBRARY)
        self._stream.flush()   # a writer killed before its first flush leaves an MCAP file
        self._skip = skip
        self.skipped = 0
        self._schema_ids: Dict[str, int] = {}
        self._channels: Dict[str, Tuple[int, str, str]] = {}  # topic -> id, type, QoS
        self.message_counts: Dict[str, int] = {}
        self.first_time: Optional[int] = None  # ns
        self.last_time: Optional[int] = None
        self._unflushed = 0
        self.closed = False

    def __enter__(self):
        """Return the open writer."""
        return self

    def __exit__(self, *exc_info):
        """Close the bag, also after an error, so that it stays readable."""
        self.close()

    @property
    def message_count(self):
        """Return the number of messages written so far."""
        return sum(self.message_counts.values())

    @property
    def unflushed_count(self):
        """Return how many messages are still only in memory."""
        return self._unflushed

    def has_topic(self, topic):
        """Return whether a channel exists for topic."""
        return topic in self._channels

    def add_topic(self, topic: str, type_name: str,
                  offered_qos_profiles: Union[str, Sequence[Any]] = '') -> None:
        """
        Create the channel of topic (and the schema of its type) unless it exists.

        Args:
            topic: the topic's name, e.g. '/candidates'.
            type_name: its message type, e.g. 'hand_codesign_msgs/msg/Candidate'; its
                definition is looked up on AMENT_PREFIX_PATH.
            offered_qos_profiles: the YAML text of ``qos_profiles_yaml`` or a list of
                profiles.

        Raises:
            DefinitionError: when the type's definition cannot be found.
        """
        self._check_open()
        if topic in self._channels:
            return
        if not isinstance(offered_qos_profiles, str):
            offered_qos_profiles = qos_profiles_yaml(offered_qos_profiles)
        if type_name not in self._schema_ids:
            definition = message_definition(type_name)
            self._schema_ids[type_name] = self._writer.register_schema(
                name=type_name, encoding=SCHEMA_ENCODING, data=definition.encode('utf-8'))
        channel_id = self._writer.register_channel(
            topic=topic, message_encoding=MESSAGE_ENCODING,
            schema_id=self._schema_ids[type_name],
            metadata={'offered_qos_profiles': offered_qos_profiles,
                      'topic_type_hash': type_hash(type_name)})
        self._channels[topic] = (channel_id, type_name, offered_qos_profiles)
        self.message_counts[topic] = 0

    def write(self, topic: str, data: bytes, log_time: Optional[int] = None,
              publish_time: Optional[int] = None) -> None:
        """
        Append one serialized message of topic unless skipped.

        Args:
            topic: a topic added with add_topic.
            data: the message serialized as CDR (rclpy.serialization.serialize_message).
            log_time: ns since the epoch; None: now.
            publish_time: ns since the epoch; None: log_time.

        Raises:
            BagWriteError: for a topic without a channel or a closed writer.
        """
        self._check_open()
        channel = self._channels.get(topic)
        if channel is None:
            raise BagWriteError(f'topic {topic!r} has no channel in {self.file_path}: '
                                'call add_topic first')
        if self._skip and message_key(topic, data) in self._skip:
            self.skipped += 1
            return
        if log_time is None:
            log_time = time.time_ns()
        if publish_time is None:
            publish_time = log_time
        self._writer.add_message(channel_id=channel[0], log_time=log_time, data=data,
                                 publish_time=publish_time)
        self.message_counts[topic] += 1
        self._unflushed += 1
        if self.first_time is None or log_time < self.first_time:
            self.first_time = log_time
        if self.last_time is None or log_time > self.last_time:
            self.last_time = log_time

    def flush(self):
        """Write the chunk in progress and flush the file, so a killed process loses nothing."""
        self._check_open()
        if self._unflushed:
            self._writer.flush()
            self._unflushed = 0

    def close(self) -> None:
        """Write the last chunk, the summary and the footer (and metadata.yaml); idempotent."""
        if self.closed:
            return
        self.closed = True
        try:
            self._add_rosbag2_record()
            self._writer.finish()
            self._stream.flush()
            os.fsync(self._stream.fileno())
        finally:
            self._stream.close()
        self._unflushed = 0
        if self.is_directory:
            self._write_metadata_yaml()

    def _add_rosbag2_record(self):
        topics = [topic_information(topic, type_name, qos, type_hash(type_name),
                                    self.message_counts[topic])
                  for topic, (_, type_name, qos) in self._channels.items()]
        add_rosbag2_record(self._writer, topics, file_information(
            self.file_path.name, self.first_time or 0, self.last_time or 0, self.message_count))

    def _check_open(self):
        if self.closed:
            raise BagWriteError(f'bag {self.file_path} is already closed')

    def _write_metadata_yaml(self):
        """Write the rosbag2 metadata.yaml of the bag directory, covering all its files."""
        write_metadata(self.bag_path)
