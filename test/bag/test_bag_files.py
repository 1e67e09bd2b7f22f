"""
Bags that outlive their recorder (bag.recovery, `hand-codesign recover`), without processes.

A killed recorder is a writer whose file stops after its last flush. What a user checks:
after `recover` independent readers (rosbags, mcap's indexed reader) take the bag, every
flushed message is there once, and a bag continued in a next file holds each message once.
"""

import contextlib
import io
import shutil
import types

from bag_samples import dds_bytes
from bag_samples import interleaved
from bag_samples import rosbag2_record
from bag_samples import sample_messages
from hand_codesign.bag.files import bag_files
from hand_codesign.bag.reader import read_run
from hand_codesign.bag.reader import read_topics
from hand_codesign.bag.recovery import continue_bag
from hand_codesign.bag.writer import BagWriter
from hand_codesign.cli import main
from hand_codesign.core.contract import CANDIDATE_TYPE
from hand_codesign.core.contract import CANDIDATES
from hand_codesign.ros import topics
from mcap.reader import make_reader
import pytest
from rosbags.rosbag2 import Reader
import yaml


def wire_messages():
    """
    Return the sample run as (topic, bytes) in publishing order, each serialized once.

    A restarted recorder receives the very bytes a publisher keeps in its history; serializing
    a message twice may differ in its padding bytes.
    """
    messages = sample_messages()
    return messages, [('/' + topic, dds_bytes(message))
                      for topic, message in interleaved(messages)]


def write_wire(writer, messages, wire, flush_every=None, first_time=1_000_000,
               topic_order=None):
    for topic in topic_order or messages:
        writer.add_topic('/' + topic, topics.type_name(topics.MESSAGE_TYPES[topic]),
                         [topics.QOS[topic]])
    for index, (topic, data) in enumerate(wire):
        writer.write(topic, data, log_time=first_time + index)
        if flush_every and (index + 1) % flush_every == 0:
            writer.flush()


def killed_bag(folder, flush_every=10):
    """Write a bag folder whose writer is 'killed': the file as it is on disk after a flush."""
    messages, wire = wire_messages()
    writer = BagWriter(folder)
    write_wire(writer, messages, wire, flush_every)
    cut = folder.parent / 'cut'
    cut.mkdir()
    shutil.copy(writer.file_path, cut / writer.file_path.name)
    flushed = writer.message_count - writer.unflushed_count
    writer.close()
    shutil.rmtree(folder)
    shutil.move(cut, folder)
    return messages, wire, flushed


def recover(path):
    """Run `hand-codesign recover path` (in this process); return code, stdout and stderr."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(['recover', str(path)])
    return types.SimpleNamespace(returncode=code, stdout=out.getvalue(),
                                 stderr=err.getvalue())


def test_recover_closes_a_killed_bag_for_independent_readers(tmp_path):
    folder = tmp_path / 'run'
    _, _, flushed = killed_bag(folder)
    assert not (folder / 'metadata.yaml').exists()
    assert read_run(folder).truncated
    done = recover(folder)
    assert done.returncode == 0, done.stderr
    assert f'{flushed} messages kept, closed and indexed' in done.stdout
    with Reader(folder) as reader:
        assert reader.message_count == flushed
        assert sum(1 for _ in reader.messages()) == flushed
    with open(next(folder.glob('*.mcap')), 'rb') as stream:
        summary = make_reader(stream).get_summary()
    assert summary.statistics.message_count == flushed and summary.chunk_indexes
    record = read_run(folder)
    assert not record.truncated and sum(record.message_counts.values()) == flushed
    # the recovered file holds the rosbag2 record its recorder would have written on close
    metadata = rosbag2_record(folder / 'run_0.mcap')
    assert metadata['message_count'] == flushed and metadata['relative_file_paths'] == [
        'run_0.mcap']
    assert sum(entry['message_count'] for entry in metadata['topics_with_message_count']) == (
        flushed)
    again = recover(folder)
    assert again.returncode == 0 and 'already closed' in again.stdout


def test_recover_names_a_missing_bag_in_one_line(tmp_path):
    done = recover(tmp_path / 'nothing')
    assert done.returncode == 2
    assert done.stderr.strip().count('\n') == 0 and 'nothing: no such file' in done.stderr


def test_continued_bag_holds_each_message_once(tmp_path):
    folder = tmp_path / 'run'
    messages, wire, flushed = killed_bag(folder, flush_every=25)
    # the restarted recorder hears the publishers' whole history again (transient-local)
    index, recorded, channels = continue_bag(folder)
    assert index == 1 and len(recorded) == flushed
    writer = BagWriter(folder, file_index=index, skip=recorded)
    for topic, type_name, offered_qos in channels:
        writer.add_topic(topic, type_name, offered_qos)
    # the topics come in another order this time: their channel ids must stay the same
    write_wire(writer, messages, wire, first_time=2_000_000,
               topic_order=list(reversed(messages)))
    writer.close()
    total = sum(len(x) for x in messages.values())
    assert writer.skipped == flushed and writer.message_count == total - flushed
    metadata = yaml.safe_load((folder / 'metadata.yaml').read_text())
    information = metadata['rosbag2_bagfile_information']
    assert information['relative_file_paths'] == ['run_0.mcap', 'run_1.mcap']
    assert information['message_count'] == total
    with Reader(folder) as reader:
        assert sum(1 for _ in reader.messages()) == total
    # each file, the recovered one and the one continued, holds its own rosbag2 record
    assert [rosbag2_record(folder / name)['message_count']
            for name in ('run_0.mcap', 'run_1.mcap')] == [flushed, total - flushed]
    record = read_run(folder)
    assert {topic.lstrip('/'): count for topic, count in record.message_counts.items()} == {
        topic: len(x) for topic, x in messages.items()}
    ids = list(record.evaluations['candidate_id'])
    assert len(ids) == len(set(ids))


def test_recover_refuses_what_is_not_a_bag(tmp_path):
    path = tmp_path / 'x.mcap'
    path.write_bytes(b'not an mcap file at all')
    done = recover(path)
    assert done.returncode == 2 and 'not an MCAP file' in done.stderr
    assert [file.name for file in tmp_path.iterdir()] == ['x.mcap']


@pytest.mark.parametrize('cut', [0, 5, 8])
def test_file_cut_off_before_its_header_becomes_an_empty_bag(tmp_path, cut):
    folder = tmp_path / 'early'
    BagWriter(folder).close()
    path = next(folder.glob('*.mcap'))
    path.write_bytes(path.read_bytes()[:cut])
    (folder / 'metadata.yaml').unlink()
    done = recover(folder)
    assert done.returncode == 0 and '0 messages kept' in done.stdout, done.stderr
    with Reader(folder) as reader:
        assert reader.message_count == 0


def test_every_reader_takes_a_bag_folder_in_the_order_its_files_were_written(tmp_path):
    # past run_9.mcap an order by name would put run_10.mcap before run_2.mcap
    folder = tmp_path / 'run'
    messages, wire = wire_messages()
    candidates = [data for topic, data in wire if topic == '/' + CANDIDATES][:12]
    for index, data in enumerate(candidates):
        writer = BagWriter(folder, file_index=index)
        writer.add_topic('/' + CANDIDATES, CANDIDATE_TYPE, [topics.QOS[CANDIDATES]])
        writer.write('/' + CANDIDATES, data, log_time=1_000_000)   # one time: files decide
        writer.close()
    written = [f'run_{index}.mcap' for index in range(12)]
    assert [path.name for path in bag_files(folder)] == written
    metadata = yaml.safe_load((folder / 'metadata.yaml').read_text())
    assert metadata['rosbag2_bagfile_information']['relative_file_paths'] == written
    expected = [message.candidate_id for message in messages[CANDIDATES][:12]]
    for with_metadata in (True, False):
        if not with_metadata:
            (folder / 'metadata.yaml').unlink()
        tables, _ = read_topics(folder, [CANDIDATE_TYPE])
        assert list(tables[CANDIDATE_TYPE]['candidate_id']) == expected
    assert continue_bag(folder)[0] == 12
