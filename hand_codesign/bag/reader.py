"""
Read a co-design run back from its bag, without ROS: ``read_run(path) -> RunRecord``.

The bag is the rosbag2-compatible MCAP the recorder writes (one ``.mcap`` file, or a rosbag2
bag directory holding ``.mcap`` files). mcap's ``StreamReader`` reads the records front to back
without seeking, so a bag whose recorder was killed still gives every complete chunk and
message before the cut; such a bag comes back with ``truncated=True`` and a warning (rosbags'
readers need the summary at the end of the file and refuse such a bag). A file that is empty,
not MCAP, or an MCAP bag without hand_codesign topics raises ``BagError`` naming the file and
what was expected.

Messages are decoded with decoders compiled from the schema text stored in the bag
(``hand_codesign.bag.cdr``, four to ten times faster than the libraries'), falling back
to the rosbags typestore built from the same schema for anything those do not handle (e.g.
big-endian CDR), and gathered per topic into column tables of numpy arrays.

GenerationSummaries are what a reader trusts most (resume rebuilds the search from them), so
in a signed run each carries an Ed25519 signature under the key its run announced in its first
RunInfo (core.run.signing; `_summary_keys`); a summary whose signature fails was forged on the
run's domain, is left out, and counted in ``RunRecord.rejected_summaries`` with a warning.
"""

import collections
import dataclasses
import pathlib
import struct
from typing import Dict, Iterable, List, Optional, Tuple, Union

from hand_codesign.bag import cdr
from hand_codesign.bag.files import bag_files
from hand_codesign.bag.files import BagError
from hand_codesign.bag.files import check_start
from hand_codesign.bag.files import Records
from hand_codesign.core.contract import CANDIDATE_TYPE
from hand_codesign.core.contract import EVALUATION_TYPE
from hand_codesign.core.contract import EVALUATOR_STATUS_TYPE
from hand_codesign.core.contract import GENERATION_SUMMARY_TYPE
from hand_codesign.core.contract import LOOP_TYPES
from hand_codesign.core.contract import MESSAGES_PACKAGE
from hand_codesign.core.contract import RUN_INFO_TYPE
from hand_codesign.core.run.runs import run_task
from hand_codesign.core.run.signing import summary_valid
from mcap.exceptions import McapError
from mcap.records import Channel
from mcap.records import Chunk
from mcap.records import Header
from mcap.records import Message
from mcap.records import Schema
from mcap.records import Statistics
from mcap.stream_reader import breakup_chunk
import numpy as np
from rosbags.serde import SerdeError
from rosbags.typesys import get_types_from_msg
from rosbags.typesys import get_typestore
from rosbags.typesys import Stores
from rosbags.typesys import TypesysError
import yaml
import zstandard

# Fields appended to a message type after bags were recorded with it: a bag of the older
# schema reads with these columns empty (no names, no values) in every row.
LATER_FIELDS = {EVALUATION_TYPE: {'outcome_names': 'names', 'outcomes': 'values'}}

# What a damaged chunk raises while it is decompressed and broken up (lz4 raises RuntimeError).
_DAMAGE_ERRORS = (McapError, struct.error, ValueError, UnicodeDecodeError, RuntimeError,
                  zstandard.ZstdError)


@dataclasses.dataclass(frozen=True)
class RunInfo:
    """The announcement of a run: everything needed to rebuild its task."""

    run_id: str
    task_name: str
    task_yaml: str
    seed: int
    algorithm: str
    iterations: int
    population: int
    world_states: int
    objective_names: tuple
    versions: tuple
    resumed_from: str
    stamp: int          # ns since the epoch, from the message
    log_time: int       # ns since the epoch, when the recorder received it
    engine: str = ''    # physics engine ('' in a bag older than the field: the task file's)
    engine_version: str = ''

    def task(self, variant=None, source='bag:run_info'):
        """
        Return the Task the run used: its task text with the run's overrides applied.

        `variant` (core.task.variant.Variant, e.g. a candidate's: its structure, a hierarchy
        check's worlds, its horizon, stage, held-out worlds or resampled draw) makes it the
        version of the run's task that candidate was evaluated on.
        """
        return run_task(self.task_yaml, source=source, seed=self.seed,
                        iterations=self.iterations, population=self.population,
                        world_states=self.world_states, variant=variant, engine=self.engine)


class Table:
    """
    Column table of the messages of one topic, in the order they were recorded.

    Every message field is a column (``table['candidate_id']``): numbers as numpy arrays,
    strings as object arrays, a numeric list field as a 2-D array when every row has the same
    length (rows left empty, e.g. of rejected evaluations, are NaN) and else as an object
    array of 1-D arrays, string lists as tuples. ``log_time`` and ``publish_time`` (ns) come
    from the bag.
    """

    def __init__(self, columns, length):
        """Wrap {name: array} columns of length rows."""
        self.columns = columns
        self.length = length

    def __len__(self):
        """Return the number of rows."""
        return self.length

    def __getitem__(self, name):
        """Return the column name."""
        try:
            return self.columns[name]
        except KeyError:
            raise KeyError(f'no column {name!r}; columns: {list(self.columns)}') from None

    def __contains__(self, name):
        """Return whether the table has column name."""
        return name in self.columns

    def row(self, index):
        """Return row index as a dict."""
        return {name: column[index] for name, column in self.columns.items()}

    def select(self, mask):
        """Return the rows where the boolean array mask is true, as a new Table."""
        mask = np.asarray(mask, dtype=bool)
        return Table({name: column[mask] for name, column in self.columns.items()},
                     int(mask.sum()))


@dataclasses.dataclass
class RunRecord:
    """Everything one run left in its bag, as plain Python and numpy objects."""

    path: str
    run_id: str
    run_info: Optional[RunInfo]  # None when the bag holds no RunInfo of the run
    candidates: Table
    evaluations: Table
    evaluator_status: Table
    generation_summaries: Table
    message_counts: dict        # topic -> messages read (all runs), in first-seen order
    run_ids: tuple              # every run id seen in the bag
    start_time: int             # log time (ns) of the first and last message read
    end_time: int
    truncated: bool = False
    warnings: list = dataclasses.field(default_factory=list)
    rejected_summaries: int = 0  # GenerationSummaries of the run left out: signature fails

    @property
    def warning(self):
        """Return all warnings as one text ('' when there are none)."""
        return '\n'.join(self.warnings)


@dataclasses.dataclass
class _Channel:
    topic: str
    schema_name: str
    schema_encoding: str
    schema_text: str
    message_encoding: str


class _Scan:
    """The raw content of an MCAP file: channels and the messages of the channels we want."""

    def __init__(self, path, wanted=LOOP_TYPES):
        self.path = path
        self.wanted = wanted   # the types whose messages are kept
        self.profile = None
        self.schemas = {}
        self.channels = {}
        self.messages = collections.defaultdict(list)   # channel id -> [(log, publish, data)]
        self.counts = collections.Counter()             # channel id -> count
        self.statistics_count = None
        self.truncated = False
        self.damage = []


def _bag_files(path):
    """
    Return the .mcap files of a bag path (a file or a rosbag2 directory) in written order.

    A directory's metadata.yaml, when there is one, says which of its files belong to the bag;
    the order is always bag.files.bag_files', the order they were written in.
    """
    if not path.exists():
        raise BagError(f'{path}: no such file or directory; expected a .mcap bag written by '
                       'the hand_codesign recorder')
    if path.is_file():
        return [path]
    metadata_path = path / 'metadata.yaml'
    if metadata_path.is_file():
        try:
            metadata = yaml.safe_load(metadata_path.read_text(encoding='utf-8'))
            names = metadata['rosbag2_bagfile_information']['relative_file_paths']
            listed = {pathlib.PurePath(name).name for name in names}
        except (yaml.YAMLError, KeyError, TypeError) as error:
            raise BagError(f'{metadata_path}: not a rosbag2 metadata file ({error})') from None
        missing = sorted(str(path / name) for name in listed if not (path / name).is_file())
        if missing:
            raise BagError(f'{metadata_path}: lists files that do not exist: {missing}')
        return [file for file in bag_files(path) if file.name in listed]
    files = bag_files(path)
    if not files:
        raise BagError(f'{path}: a directory without .mcap files or metadata.yaml; expected '
                       'a bag written by the hand_codesign recorder')
    return files


def scan_file(path, wanted=LOOP_TYPES):
    """
    Return the _Scan of one MCAP file, read front to back by mcap's StreamReader.

    The messages of the types in `wanted` are kept, the others only counted.

    Reading stops cleanly where the file is cut off (``truncated``); a chunk that cannot be
    decompressed or broken up is reported in ``damage`` and skipped.
    """
    check_start(path)
    scan = _Scan(path, wanted)
    records = Records(path, chunks=True)
    for record in records:
        if type(record) is Chunk:
            _read_chunk(scan, record)
        else:
            _read_record(scan, record)
    scan.truncated = records.cut or records.damage is not None
    if records.damage is not None:
        scan.damage.append(f'a record after message {sum(scan.counts.values())} is '
                           f'damaged ({records.damage}); the rest of the file is not read')
    return scan


def _read_chunk(scan, chunk):
    """Read the records inside one chunk, or note that the chunk is damaged."""
    try:
        records = breakup_chunk(chunk)
    except _DAMAGE_ERRORS as error:
        scan.damage.append(f'a chunk of messages logged from {chunk.message_start_time} to '
                           f'{chunk.message_end_time} ns is damaged and skipped: {error}')
        return
    for record in records:
        _read_record(scan, record)


def _read_record(scan, record):
    """Take what we need from one record (top-level or inside a chunk)."""
    kind = type(record)
    if kind is Message:
        channel_id = record.channel_id
        scan.counts[channel_id] += 1
        if channel_id in scan.messages:
            scan.messages[channel_id].append((record.log_time, record.publish_time,
                                              record.data))
    elif kind is Schema:
        scan.schemas.setdefault(record.id, (record.name, record.encoding,
                                            record.data.decode('utf-8', 'replace')))
    elif kind is Channel:
        if record.id in scan.channels:
            return
        name, encoding, text = scan.schemas.get(record.schema_id, ('', '', ''))
        scan.channels[record.id] = _Channel(record.topic, name, encoding, text,
                                            record.message_encoding)
        if name in scan.wanted:
            scan.messages[record.id]   # creates the list: messages of this channel are kept
    elif kind is Header:
        scan.profile = record.profile
    elif kind is Statistics:
        scan.statistics_count = record.message_count


def _decoder(channel):
    """Return decode(bytes) -> tuple and the field names for the messages of a channel."""
    try:
        return (cdr.compile_schema(channel.schema_name, channel.schema_text),
                cdr.field_names(channel.schema_name, channel.schema_text))
    except cdr.UnsupportedSchema:
        return _generic_decoder(channel)


def _generic_decoder(channel):
    """Return a decoder of the rosbags typestore of a channel's schema, giving tuples as ours."""
    type_name = cdr.full_type_name(channel.schema_name)
    store = get_typestore(Stores.EMPTY)
    try:
        store.register(get_types_from_msg(channel.schema_text, type_name))
    except (TypesysError, ValueError) as error:
        raise cdr.UnsupportedSchema(f'cannot parse the schema of {type_name}: {error}') from None
    names = [name for name, _ in store.fielddefs[type_name][1]]

    def decode(data):
        try:
            message = store.deserialize_cdr(data, type_name)
        except SerdeError as error:
            raise ValueError(str(error)) from None
        return tuple(_plain(getattr(message, name)) for name in names)

    return decode, names


def _plain(value):
    """Return a generically decoded field in the form of the compiled decoders."""
    if hasattr(value, 'sec') and hasattr(value, 'nanosec'):
        return value.sec * 1_000_000_000 + value.nanosec
    if isinstance(value, (list, tuple)) and value and isinstance(value[0], (int, float)):
        return np.asarray(value)
    return value


def _decode_channel(channel, rows, problems):
    """Return (field names, decoded tuples, log times, publish times) of one channel."""
    try:
        decode, names = _decoder(channel)
    except cdr.UnsupportedSchema as error:
        problems.append(f'the {len(rows)} messages on {channel.topic} cannot be decoded '
                        f'({error}) and were skipped')
        return [], [], [], []
    values = []
    log_times = []
    publish_times = []
    failures = 0
    for log_time, publish_time, data in rows:
        try:
            try:
                values.append(decode(data))
            except cdr.UnsupportedSchema:   # e.g. a big-endian message: rosbags reads it
                decode, names = _generic_decoder(channel)
                values.append(decode(data))
        except (ValueError, struct.error, UnicodeDecodeError, IndexError):
            failures += 1
            continue
        log_times.append(log_time)
        publish_times.append(publish_time)
    if failures:
        problems.append(f'{failures} messages on {channel.topic} could not be decoded and '
                        'were skipped')
    return names, values, log_times, publish_times


def _column(values):
    """Return one table column from the list of a field's values."""
    if not values:
        return np.array([], dtype=float)
    first = values[0]
    if isinstance(first, np.ndarray):
        lengths = {len(value) for value in values}
        nonempty = lengths - {0}
        if len(nonempty) <= 1:
            width = nonempty.pop() if nonempty else 0
            dtype = np.result_type(*{value.dtype for value in values})
            if 0 in lengths and width:
                dtype = np.result_type(dtype, np.float64)
                matrix = np.full((len(values), width), np.nan, dtype=dtype)
                for index, value in enumerate(values):
                    if len(value):
                        matrix[index] = value
                return matrix
            return np.array(values, dtype=dtype).reshape(len(values), width)
        column = np.empty(len(values), dtype=object)
        column[:] = [np.array(value) for value in values]
        return column
    if isinstance(first, (list, tuple)):
        rows = [tuple(value) for value in values]
        column = np.empty(len(rows), dtype=object)
        try:
            # Name lists repeat row after row: rows share one tuple per distinct list.
            shared = {}
            column[:] = [shared.setdefault(row, row) for row in rows]
        except TypeError:   # unhashable rows: lists of nested messages holding arrays
            column[:] = rows
        return column
    if isinstance(first, str):
        return np.array(values, dtype=object)
    return np.array(values)


def _table(names, values, log_times, publish_times):
    """Return a Table of decoded tuples."""
    columns = {'log_time': np.array(log_times, dtype=np.int64),
               'publish_time': np.array(publish_times, dtype=np.int64)}
    if values:
        for name, field_values in zip(names, zip(*values)):
            columns[name] = _column(list(field_values))
    else:
        for name in names:
            columns[name] = np.array([], dtype=float)
    return Table(columns, len(values))


def _with_later_fields(type_name, table):
    """Return the table with an empty column for each LATER_FIELDS field its schema lacks."""
    for name, kind in LATER_FIELDS.get(type_name, {}).items():
        if name not in table.columns:
            if kind == 'names':
                column = np.empty(len(table), dtype=object)
                column.fill(())  # no names in any row
            else:
                column = np.zeros((len(table), 0))
            table.columns[name] = column
    return table


def _empty_table():
    return Table({'log_time': np.array([], dtype=np.int64),
                  'publish_time': np.array([], dtype=np.int64)}, 0)


def _concatenate(tables):
    """Return the rows of several tables of one type (several channels or files) as one."""
    tables = [table for table in tables if len(table)]
    if not tables:
        return _empty_table()
    if len(tables) == 1:
        return tables[0]
    names = list(tables[0].columns)
    order = np.argsort(np.concatenate([table['log_time'] for table in tables]), kind='stable')
    columns = {}
    for name in names:
        parts = [table.columns.get(name) for table in tables]
        try:
            merged = np.concatenate(parts)
        except ValueError:
            rows = [row for part in parts for row in part]
            merged = np.empty(len(rows), dtype=object)
            merged[:] = rows
        columns[name] = merged[order]
    return Table(columns, len(order))


def _run_info(table, index):
    """Return the RunInfo dataclass of row index of the run_info table."""
    row = table.row(index)
    return RunInfo(
        run_id=str(row.get('run_id', '')),
        task_name=str(row.get('task_name', '')),
        task_yaml=str(row.get('task_yaml', '')),
        seed=int(row.get('seed', 0)),
        algorithm=str(row.get('algorithm', '')),
        iterations=int(row.get('iterations', 0)),
        population=int(row.get('population', 0)),
        world_states=int(row.get('world_states', 0)),
        objective_names=tuple(row.get('objective_names', ())),
        versions=tuple(row.get('versions', ())),
        resumed_from=str(row.get('resumed_from', '')),
        stamp=int(row.get('stamp', 0)),
        log_time=int(row['log_time']),
        engine=str(row.get('engine', '')),
        engine_version=str(row.get('engine_version', '')),
    )


def _choose_run(run_id, tables, warnings):
    """Return the run to read: the one asked for, else the bag's first announced run."""
    run_info = tables[RUN_INFO_TYPE]
    seen = collections.Counter()
    for table in tables.values():
        if len(table) and 'run_id' in table:
            seen.update(run for run in table['run_id'] if run)
    announced = list(dict.fromkeys(run_info['run_id'])) if len(run_info) else []
    all_runs = tuple(dict.fromkeys(announced + list(seen)))
    if run_id is not None:
        if run_id not in all_runs:
            raise BagError(f'run {run_id!r} is not in the bag; runs in it: {list(all_runs)}')
        return run_id, all_runs
    if announced:
        chosen = announced[0]
        if len(announced) > 1:
            warnings.append(f'the bag announces {len(announced)} runs {announced}; reading the '
                            f'first, {chosen!r} (pass run_id to choose)')
        return chosen, all_runs
    if seen:
        chosen = seen.most_common(1)[0][0]
        warnings.append(f'the bag holds no RunInfo; reading run {chosen!r}, the run of most '
                        'messages')
        return chosen, all_runs
    return '', all_runs


def read_topics(path: Union[str, pathlib.Path],
                type_names: Iterable[str]) -> Tuple[Dict[str, 'Table'], List[str]]:
    """
    Return every message of those types in the bag at path, a Table per type.

    For the topics beside the loop's (the rig's trials); nested fields (a PoseStamped's
    header and pose) come as nested tuples, times as integer nanoseconds.

    Args:
        path: a .mcap file or a rosbag2 directory.
        type_names: message types, e.g. 'hand_codesign_msgs/msg/TrialStatus'.

    Returns:
        ({type name: Table of its messages, one row each, in log time order}, warnings: one
        line for each damaged part of the bag that was skipped).
    """
    warnings: List[str] = []
    parts = collections.defaultdict(list)
    for file in _bag_files(pathlib.Path(path)):
        scan = scan_file(file, tuple(type_names))
        warnings.extend(f'{scan.path}: {problem}' for problem in scan.damage)
        for channel_id, channel in scan.channels.items():
            if channel.schema_name in type_names:
                rows = scan.messages.get(channel_id, [])
                parts[channel.schema_name].append(
                    _table(*_decode_channel(channel, rows, warnings)))
    return {name: _concatenate(parts[name]) for name in type_names}, warnings


def read_run(path: Union[str, pathlib.Path], run_id: Optional[str] = None) -> RunRecord:
    """
    Return the RunRecord of one run of the bag at path.

    Args:
        path: a .mcap file or a rosbag2 directory.
        run_id: selects a run when the bag holds several (None: the first announced run);
            messages of other runs are counted in ``message_counts`` and otherwise left out.

    Returns:
        The RunRecord: the run's RunInfo and a Table (one row per message) of its
        candidates, evaluations (objectives in m and rad), evaluator statuses and
        generation summaries, with log times in ns and the bag's warnings.

    Raises:
        BagError: for a missing, empty, non-MCAP or foreign bag.
    """
    path = pathlib.Path(path)
    files = _bag_files(path)
    scans = [scan_file(file) for file in files]
    warnings = []
    truncated = False
    for scan in scans:
        if scan.truncated:
            truncated = True
            warnings.append(
                f'{scan.path} is truncated (its recorder was probably killed): read '
                f'{sum(scan.counts.values())} complete messages before the cut, the rest is '
                'lost')
        warnings.extend(f'{scan.path}: {problem}' for problem in scan.damage)
        if scan.profile not in (None, 'ros2'):
            warnings.append(f'{scan.path}: MCAP profile is {scan.profile!r}, not "ros2"')
        if (not scan.truncated and scan.statistics_count is not None
                and scan.statistics_count != sum(scan.counts.values())):
            warnings.append(f'{scan.path}: its statistics count {scan.statistics_count} '
                            f'messages but {sum(scan.counts.values())} were found')

    loop_channels = [(scan, channel_id, channel) for scan in scans
                     for channel_id, channel in scan.channels.items()
                     if channel.schema_name.startswith(MESSAGES_PACKAGE + '/')]
    if not loop_channels:
        found = sorted({f'{channel.topic} [{channel.schema_name or "no schema"}]'
                        for scan in scans for channel in scan.channels.values()})
        cut = ' (the file is truncated)' if truncated else ''
        raise BagError(
            f'{path}: an MCAP file without hand_codesign topics{cut}; found '
            f'{found or "no topics"}, expected topics of types {", ".join(LOOP_TYPES)} as '
            'written by the hand_codesign recorder')

    message_counts: Dict[str, int] = {}
    for scan in scans:
        for channel_id, channel in scan.channels.items():
            message_counts[channel.topic] = (message_counts.get(channel.topic, 0)
                                             + scan.counts.get(channel_id, 0))

    parts = collections.defaultdict(list)
    decoded = []   # (type name, (field names, values, log times, publish times))
    for scan, channel_id, channel in loop_channels:
        if channel.schema_name not in LOOP_TYPES:
            continue
        if channel.schema_encoding != 'ros2msg' or channel.message_encoding != 'cdr':
            warnings.append(f'{channel.topic}: schema encoding {channel.schema_encoding!r} / '
                            f'message encoding {channel.message_encoding!r} is not ros2msg / '
                            'cdr; skipped')
            continue
        rows = scan.messages.get(channel_id, [])
        decoded.append((channel.schema_name, _decode_channel(channel, rows, warnings)))
    forged = _drop_forged_summaries(decoded)
    for name, columns in decoded:
        parts[name].append(_with_later_fields(name, _table(*columns)))
    tables = {name: _concatenate(parts[name]) for name in LOOP_TYPES}

    chosen, all_runs = _choose_run(run_id, tables, warnings)
    if forged[chosen]:
        warnings.append(f'left out {forged[chosen]} GenerationSummary message(s) of run '
                        f"{chosen!r} whose signature fails or repeats: not its optimizer's "
                        "(forged on the run's domain?)")
    for name in LOOP_TYPES:
        table = tables[name]
        if not len(table) or 'run_id' not in table:
            continue
        keep = table['run_id'] == chosen
        if name == EVALUATOR_STATUS_TYPE:
            keep |= table['run_id'] == ''   # evaluators waiting for a run announce ''
        elif not keep.all():
            warnings.append(f'left out {int((~keep).sum())} {name.split("/")[-1]} messages of '
                            'other runs')
        tables[name] = table.select(keep)

    run_info_table = tables[RUN_INFO_TYPE]
    run_info = _run_info(run_info_table, 0) if len(run_info_table) else None
    if run_info is None:
        warnings.append(f'{path}: no RunInfo of run {chosen!r}: the task and seed are unknown')
    times = np.concatenate([table['log_time'] for table in tables.values()])
    return RunRecord(
        path=str(path),
        run_id=chosen,
        run_info=run_info,
        candidates=tables[CANDIDATE_TYPE],
        evaluations=tables[EVALUATION_TYPE],
        evaluator_status=tables[EVALUATOR_STATUS_TYPE],
        generation_summaries=tables[GENERATION_SUMMARY_TYPE],
        message_counts=message_counts,
        run_ids=all_runs,
        start_time=int(times.min()) if len(times) else 0,
        end_time=int(times.max()) if len(times) else 0,
        truncated=truncated,
        warnings=warnings,
        rejected_summaries=forged[chosen],
    )


def _summary_keys(decoded):
    """
    Return {run id: RunInfo.summary_key} of each run's first RunInfo that has a key.

    First: by the time its publisher wrote it (the recorder may hear a forger's copy, made
    after the run's own, before the run's own), then by log time. A RunInfo without a key
    cannot make a signed run's summaries unchecked: an optimizer with a key always sends one.
    """
    first = {}
    for type_name, (names, values, log_times, publish_times) in decoded:
        if type_name != RUN_INFO_TYPE or 'summary_key' not in names:
            continue   # a bag of a run before summaries were signed
        run_at, key_at = names.index('run_id'), names.index('summary_key')
        for value, log_time, publish_time in zip(values, log_times, publish_times):
            run, key = value[run_at], bytes(value[key_at])
            if key and (run not in first or (publish_time, log_time) < first[run][0]):
                first[run] = ((publish_time, log_time), key)
    return {run: key for run, (_, key) in first.items()}


def _drop_forged_summaries(decoded):
    """
    Leave out the forged GenerationSummaries of decoded; return their count per run id.

    Forged: its signature fails or repeats (a genuine summary published again). A run whose
    first RunInfo has an empty summary_key (unsigned), or none, keeps all its summaries:
    nothing can tell them apart.
    """
    keys = _summary_keys(decoded)
    forged = collections.Counter()
    seen = set()
    for index, (type_name, (names, values, log_times, publish_times)) in enumerate(decoded):
        if type_name != GENERATION_SUMMARY_TYPE or not values:
            continue
        run_at = names.index('run_id')
        keep = [_genuine(keys.get(value[run_at], b''), names, value, seen) for value in values]
        for value, kept in zip(values, keep):
            forged[value[run_at]] += not kept
        columns = ([item for item, kept in zip(column, keep) if kept]
                   for column in (values, log_times, publish_times))
        decoded[index] = (type_name, (names, *columns))
    return forged


def _genuine(key, names, value, seen):
    """
    Return whether a decoded GenerationSummary is signed under key (b'': unsigned run).

    seen: the signatures taken so far; a repeated one is refused, a new one added.
    """
    if not key:
        return True
    if 'signature' not in names:
        return False
    summary = dict(zip(names, value))
    signature = bytes(summary['signature'])
    if signature in seen or not summary_valid(key, summary):
        return False
    seen.add(signature)
    return True
