"""read_run gives a run back from its bag, and says clearly what is wrong with a bad one."""

from bag_samples import dds_bytes
from bag_samples import interleaved
from bag_samples import sample_messages
from bag_samples import TASK_YAML
from bag_samples import write_bag
from hand_codesign.analysis.bag import BagError
from hand_codesign.analysis.bag import read_run
from hand_codesign.ros import topics
from hand_codesign.ros.mcap_writer import BagWriter
from mcap.reader import make_reader
import numpy as np
import pytest
from rclpy.serialization import serialize_message
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
