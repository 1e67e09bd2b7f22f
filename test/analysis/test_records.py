"""What the analysis verbs read from a bag: statuses, recorded results, which design is best."""

import copy

from bag_samples import sample_messages
from bag_samples import write_bag
from hand_codesign.analysis import records
from hand_codesign.errors import UserError
from hand_codesign.ros import topics
import numpy as np
import pytest


@pytest.fixture(scope='module')
def sample(tmp_path_factory):
    """Return (messages, RunRecord) of a sample run with one duplicate answer."""
    messages = sample_messages(generations=2, population=6, worlds=2)
    duplicate = copy.deepcopy(next(m for m in messages[topics.EVALUATIONS]
                                   if m.candidate_id == 2))
    duplicate.evaluator_id = 'late-host'
    duplicate.fitness = -1.0
    messages[topics.EVALUATIONS].append(duplicate)
    return messages, messages_record(tmp_path_factory.mktemp('records') / 'run.mcap', messages)


def messages_record(path, messages):
    write_bag(str(path), messages)
    return records.open_run(path)


def test_every_answer_has_its_status(sample):
    _, record = sample
    rows = records.evaluation_rows(record)
    by_id = {}
    for candidate_id, status, evaluator in zip(rows.candidate_id.tolist(), rows.status,
                                               rows.evaluator_id):
        by_id.setdefault(candidate_id, []).append((status, evaluator))
    assert by_id[5] == [('rejected', 'host-7')]
    assert by_id[2] == [('ok', 'host-0'), ('duplicate', 'late-host')]
    assert sum(rows.ok) == 11
    assert rows.gene_names[:1] == ['finger0.segment0.length']
    assert rows.genes.shape == (13, 6) and not np.isnan(rows.genes).any()


def test_recorded_evaluations_take_the_first_successful_answer(sample):
    messages, record = sample
    recorded = records.recorded_evaluations(record)
    assert sorted(recorded) == [i for i in range(12) if i != 5]
    first = next(m for m in messages[topics.EVALUATIONS] if m.candidate_id == 2)
    assert recorded[2].tolist() == list(first.objectives)


def test_the_best_design_is_the_optimizer_choice_of_the_last_summary(sample):
    _, record = sample
    assert records.best_candidate_id(record) == 6        # best_candidate_id of generation 1
    design = records.recorded_design(record, 6)
    assert design.generation == 1 and design.structure == (2, 2)
    assert design.x.shape == (6,)


def test_ranked_designs_are_ordered_by_fitness_within_a_generation(sample):
    messages, record = sample
    of_generation = [m for m in messages[topics.EVALUATIONS]
                     if m.generation == 1 and m.status == 0]
    expected = sorted(of_generation, key=lambda m: (m.fitness, m.candidate_id))
    assert records.ranked_candidate_id(record, 1, 0) == expected[0].candidate_id
    assert records.ranked_candidate_id(record, 1, 2) == expected[2].candidate_id
    with pytest.raises(UserError, match='--rank 9: generation 1 has 6 evaluated designs'):
        records.ranked_candidate_id(record, 1, 9)
    with pytest.raises(UserError, match=r'no successful evaluation in generation 4 '
                                        r'\(generations in the bag: 0..1\)'):
        records.ranked_candidate_id(record, 4)


def test_a_bag_without_run_info_says_what_needs_it(sample, tmp_path):
    messages, _ = sample
    without = {topic: values for topic, values in messages.items() if topic != topics.RUN_INFO}
    record = messages_record(tmp_path / 'no-info.mcap', without)
    with pytest.raises(UserError, match='holds no RunInfo .* rebuilding the task needs them'):
        records.run_task_of(record)
    assert records.objective_names_of(record) == ['position_1', 'orientation_1']


def test_a_missing_bag_is_a_user_error(tmp_path):
    with pytest.raises(UserError, match='no-such-bag'):
        records.open_run(tmp_path / 'no-such-bag')


def test_paths_beside_a_bag(tmp_path):
    folder = tmp_path / 'run-7'
    folder.mkdir()
    assert records.beside_bag(folder, '_report') == tmp_path / 'run-7_report'
    single = tmp_path / 'run-8.mcap'
    single.write_bytes(b'')
    assert records.beside_bag(single, '_report') == tmp_path / 'run-8_report'
