"""read_run gives a run back from its bag, and says clearly what is wrong with a bad one."""

from analysis_run import decoded_messages
from bag_samples import dds_bytes
from bag_samples import interleaved
from bag_samples import sample_messages
from bag_samples import TASK_YAML
from bag_samples import write_bag
from hand_codesign.analysis import records
from hand_codesign.bag import cdr
from hand_codesign.bag.reader import BagError
from hand_codesign.bag.reader import read_run
from hand_codesign.bag.writer import BagWriter
from hand_codesign.bag.writer import message_definition
from hand_codesign.core.contract import EVALUATION_TYPE
from hand_codesign.ros import topics
from mcap.reader import make_reader
from mcap.writer import Writer
import numpy as np
import pytest
from rclpy.serialization import serialize_message
from rosbags.highlevel import AnyReader
from std_msgs.msg import String


def test_good_bag_gives_the_run_as_published(tmp_path):
    messages = sample_messages(generations=3, population=12, worlds=3)
    path = tmp_path / 'run.mcap'
    write_bag(path, messages)
    record = read_run(path)

    assert not record.truncated and record.warnings == []
    assert record.run_id == 'run-1' and record.run_ids == ('run-1',)
    info = record.run_info
    assert info.task_yaml == TASK_YAML and info.seed == 4 and info.algorithm == 'cma'
    assert info.objective_names == ('position_1', 'orientation_1')
    assert info.stamp == 1_700_000_000 * 10**9 + 123
    task = info.task()
    assert (task.name, task.seed, task.iterations, task.population, task.num_world_states) == (
        'task5', 4, 3, 12, 3)
    assert record.message_counts == {'/' + topic: len(values)
                                     for topic, values in messages.items()}

    candidates = record.candidates
    sent = messages[topics.CANDIDATES]
    assert len(candidates) == 36
    np.testing.assert_array_equal(candidates['candidate_id'], [m.candidate_id for m in sent])
    np.testing.assert_array_equal(candidates['genome'], [list(m.genome) for m in sent])
    assert candidates['genome_names'][0] == tuple(sent[0].genome_names)
    np.testing.assert_array_equal(candidates['structure'][0], [2, 2])

    evaluations = record.evaluations
    sent = messages[topics.EVALUATIONS]
    ok = evaluations['status'] == 0
    assert len(evaluations) == 36 and int((~ok).sum()) == 1
    rejected = evaluations.row(int(np.flatnonzero(~ok)[0]))
    assert rejected['candidate_id'] == 5 and rejected['reason'] == 'genome has NaN — rejected'
    assert np.isnan(rejected['objectives']).all()
    np.testing.assert_array_equal(evaluations['objectives'][ok],
                                  [list(m.objectives) for m in sent if m.status == 0])
    assert evaluations['world_objectives'].shape == (36, 3 * 2)
    np.testing.assert_array_equal(evaluations['fitness'][ok],
                                  [m.fitness for m in sent if m.status == 0])
    assert evaluations['collision'].dtype == bool
    assert np.all(np.diff(evaluations['log_time']) > 0)

    summaries = record.generation_summaries
    assert list(summaries['generation']) == [0, 1, 2]
    assert list(summaries['final']) == [False, False, True]
    assert summaries['stop_reason'][-1] == 'iterations'
    np.testing.assert_array_equal(summaries['best'], [[0.1, 0.2]] * 3)
    # an evaluator waiting for a run announces run_id '' and is kept with the run's statuses
    assert len(record.evaluator_status) == len(messages[topics.EVALUATOR_STATUS])


def test_bag_directory_reads_like_its_file(tmp_path):
    messages = sample_messages(generations=1)
    write_bag(tmp_path / 'bag', messages)
    record = read_run(tmp_path / 'bag')
    assert len(record.candidates) == len(messages[topics.CANDIDATES])
    assert not record.truncated


def test_truncated_bag_gives_what_was_flushed_and_says_so(tmp_path):
    messages = sample_messages(generations=4, population=20)
    total = sum(len(values) for values in messages.values())
    path = tmp_path / 'full.mcap'
    # flushed every 10 messages, as the recorder does periodically
    writer = write_bag(path, messages, flush_every=10, close=False)
    writer.flush()
    flushed_size = path.stat().st_size
    writer.close()
    # killed after the last flush: every message is there, only the summary is missing
    killed = tmp_path / 'killed.mcap'
    killed.write_bytes(path.read_bytes()[:flushed_size])
    record = read_run(killed)
    assert record.truncated
    assert 'truncated' in record.warning and 'killed.mcap' in record.warning
    assert sum(record.message_counts.values()) == total
    assert record.run_info.seed == 4

    previous = 0
    # the first chunk holds every schema (the rig's and the Candidate's are long): cut beyond it
    for fraction in (0.45, 0.7, 0.95):
        cut = tmp_path / f'cut_{fraction}.mcap'
        cut.write_bytes(path.read_bytes()[:int(flushed_size * fraction)])
        record = read_run(cut)
        count = sum(record.message_counts.values())
        assert record.truncated, fraction
        # whole chunks of 10 messages survive; the cut one is lost
        assert count % 10 == 0 and previous < count < total, (fraction, count)
        previous = count
        candidate_ids = record.candidates['candidate_id']
        np.testing.assert_array_equal(candidate_ids, np.arange(len(candidate_ids)))


def test_bag_cut_in_its_header_has_no_loop_topics(tmp_path):
    path = tmp_path / 'full.mcap'
    write_bag(path, sample_messages(generations=1))
    cut = tmp_path / 'cut.mcap'
    cut.write_bytes(path.read_bytes()[:20])
    with pytest.raises(BagError, match='truncated'):
        read_run(cut)


def test_mcap_bag_of_another_program_is_named_as_such(tmp_path):
    path = tmp_path / 'chatter.mcap'
    with BagWriter(path) as writer:
        writer.add_topic('/chatter', 'std_msgs/msg/String')
        writer.write('/chatter', serialize_message(String(data='hello')))
    with pytest.raises(BagError) as error:
        read_run(path)
    text = str(error.value)
    assert 'chatter.mcap' in text and 'without hand_codesign topics' in text
    assert '/chatter [std_msgs/msg/String]' in text


def test_random_bytes_are_not_mcap(tmp_path):
    path = tmp_path / 'noise.mcap'
    path.write_bytes(np.random.default_rng(1).bytes(5000))
    with pytest.raises(BagError, match='noise.mcap: not an MCAP file'):
        read_run(path)


def test_empty_file_and_missing_path(tmp_path):
    path = tmp_path / 'empty.mcap'
    path.write_bytes(b'')
    with pytest.raises(BagError, match='empty.mcap: empty file'):
        read_run(path)
    with pytest.raises(BagError, match='no such file'):
        read_run(tmp_path / 'missing.mcap')
    (tmp_path / 'folder').mkdir()
    with pytest.raises(BagError, match='without .mcap files'):
        read_run(tmp_path / 'folder')


def test_two_runs_in_one_bag_are_told_apart(tmp_path):
    first = sample_messages(run_id='run-a', generations=1, population=4)
    second = sample_messages(run_id='run-b', generations=2, population=4, seed=1)
    merged = {topic: first[topic] + second[topic] for topic in first}
    path = tmp_path / 'two.mcap'
    write_bag(path, merged)
    record = read_run(path)
    assert record.run_id == 'run-a' and set(record.run_ids) == {'run-a', 'run-b'}
    assert len(record.candidates) == 4
    assert any('2 runs' in warning for warning in record.warnings)
    other = read_run(path, run_id='run-b')
    assert len(other.candidates) == 8 and other.run_info.run_id == 'run-b'
    with pytest.raises(BagError, match='run-c'):
        read_run(path, run_id='run-c')


@pytest.mark.parametrize('compression', ['lz4', 'none'])
def test_bags_of_other_chunk_compressions_read_alike(tmp_path, compression):
    messages = sample_messages(generations=2)
    reference = read_run(write_bag(tmp_path / 'zstd.mcap', messages).file_path)
    path = tmp_path / f'{compression}.mcap'
    writer = BagWriter(path, compression=compression)
    for topic in messages:
        writer.add_topic('/' + topic, topics.type_name(topics.MESSAGE_TYPES[topic]),
                         [topics.QOS[topic]])
    for index, (topic, message) in enumerate(interleaved(messages)):
        writer.write('/' + topic, dds_bytes(message), log_time=1_000_000 + index)
    writer.close()
    record = read_run(path)
    assert record.warnings == [] and record.message_counts == reference.message_counts
    for name, key in (('candidates', 'genome'), ('evaluations', 'objectives'),
                      ('generation_summaries', 'best')):
        table, expected = getattr(record, name), getattr(reference, name)
        assert list(table.columns) == list(expected.columns)
        np.testing.assert_array_equal(table[key], expected[key])


def test_a_damaged_chunk_is_skipped_and_the_rest_is_read(tmp_path):
    messages = sample_messages(generations=4, population=20)
    total = sum(len(values) for values in messages.values())
    path = tmp_path / 'damaged.mcap'
    write_bag(path, messages, flush_every=10)   # chunks of 10 messages
    with open(path, 'rb') as stream:
        chunks = make_reader(stream).get_summary().chunk_indexes
    # the chunk record: opcode, length, start and end times, size, crc, "zstd", records length
    data_start = chunks[2].chunk_start_offset + 1 + 8 + 8 + 8 + 8 + 4 + 4 + 4 + 8
    damaged = bytearray(path.read_bytes())
    damaged[data_start:data_start + 4] = bytes(4)   # the zstd frame's magic number
    path.write_bytes(bytes(damaged))
    record = read_run(path)
    assert not record.truncated
    assert any('damaged' in warning for warning in record.warnings), record.warnings
    assert sum(record.message_counts.values()) == total - 10
    assert len(record.candidates) + len(record.evaluations) < 2 * 80
    assert record.run_info.seed == 4


def write_bag_before_outcomes(path, messages_by_topic):
    """
    Write a bag as recorders did before Evaluation had outcome_names and outcomes.

    mcap's own writer, the Evaluation schema cut before those fields, and each Evaluation's
    bytes cut where that schema's fields end (padded to 4 bytes, as DDS sends them).
    """
    current = message_definition(EVALUATION_TYPE)
    older = current[:current.index('string[] outcome_names')]
    fields_end = cdr.compile_schema(EVALUATION_TYPE, older).message_end
    with open(path, 'wb') as stream:
        writer = Writer(stream)
        writer.start(profile='ros2', library='test')
        channels = {}
        for topic, messages in messages_by_topic.items():
            type_name = topics.type_name(topics.MESSAGE_TYPES[topic])
            text = older if type_name == EVALUATION_TYPE else message_definition(type_name)
            schema = writer.register_schema(type_name, 'ros2msg', text.encode())
            channels[topic] = writer.register_channel('/' + topic, 'cdr', schema)
        for index, (topic, message) in enumerate(interleaved(messages_by_topic)):
            data = dds_bytes(message)
            if topic == topics.EVALUATIONS:
                end = fields_end(data)
                data = data[:4 + ((end - 4 + 3) & ~3)]
            writer.add_message(channels[topic], log_time=1_000_000 + index, data=data,
                               publish_time=1_000_000 + index)
        writer.finish()


def test_a_bag_from_before_outcomes_reads_with_them_empty(tmp_path):
    messages = sample_messages(generations=2, population=6)
    old, new = tmp_path / 'old.mcap', tmp_path / 'new.mcap'
    write_bag_before_outcomes(old, messages)
    write_bag(new, messages)
    older, newer = read_run(old), read_run(new)
    assert older.warnings == [] and len(older.evaluations) == len(newer.evaluations) == 12
    assert older.evaluations['outcomes'].shape == (12, 0)
    assert set(older.evaluations['outcome_names']) == {()}
    for name in newer.evaluations.columns:
        assert str(older.evaluations[name]) == str(newer.evaluations[name]), name
    assert records.told_outcomes(older) == {}
    recorded = records.recorded_evaluations(older)
    assert recorded and all(isinstance(value, np.ndarray) for value in recorded.values())


def test_outcomes_read_back_with_our_reader_and_independent_ones(tmp_path):
    messages = sample_messages(generations=2, population=6)
    for message in messages[topics.EVALUATIONS]:
        if message.status == 0:
            message.outcome_names = ['limit_rest', 'touch']
            message.outcomes = [message.candidate_id / 16, 0.75]
    path = tmp_path / 'run.mcap'
    write_bag(path, messages)
    record = read_run(path)
    ok = record.evaluations['status'] == 0
    np.testing.assert_array_equal(record.evaluations['outcomes'][ok], [
        [m.candidate_id / 16, 0.75] for m in messages[topics.EVALUATIONS] if m.status == 0])
    assert record.evaluations['outcome_names'][0] == ('limit_rest', 'touch')
    told = records.told_outcomes(record)
    assert told[3][0] == ('limit_rest', 'touch') and told[3][1].tolist() == [3 / 16, 0.75]
    decoded = decoded_messages(path, topics.EVALUATIONS)
    with AnyReader([path]) as reader:
        connections = [c for c in reader.connections if c.topic == '/' + topics.EVALUATIONS]
        independent = [reader.deserialize(raw, connection.msgtype)
                       for connection, _, raw in reader.messages(connections=connections)]
    for messages_read in (decoded, independent):
        assert [list(m.outcomes) for m in messages_read] == [
            list(m.outcomes) for m in messages[topics.EVALUATIONS]]
        assert [list(m.outcome_names) for m in messages_read] == [
            list(m.outcome_names) for m in messages[topics.EVALUATIONS]]
