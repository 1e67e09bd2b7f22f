"""Resuming an interrupted run from its bag reaches the result of the uninterrupted run."""

import dataclasses
import json
import shutil

from analysis_run import BUDGET
from analysis_run import copy_bag
from analysis_run import decoded_messages
from analysis_run import ROOT
from analysis_run import run_cli
from analysis_run import run_codesign
from hand_codesign.analysis.resume import recorded_evaluations
from hand_codesign.analysis.resume import resume_point
from hand_codesign.bag.reader import read_run
from hand_codesign.core.evaluate import evaluate
from hand_codesign.core.run.runs import load_run_task
from hand_codesign.core.search.resume import extended_task
from hand_codesign.errors import UserError
from hand_codesign.ros import topics
import numpy as np
import pytest


@pytest.mark.system
def test_recorded_evaluations_are_what_the_optimizer_was_told(real_run):
    recorded = recorded_evaluations(read_run(real_run.bag))
    evaluations = decoded_messages(real_run.mcap, topics.EVALUATIONS)
    assert sorted(recorded) == sorted({message.candidate_id for message in evaluations})
    assert len(recorded) == 24
    for message in evaluations:
        assert np.array_equal(recorded[message.candidate_id], message.objectives)


def interrupted_copy(real_run, path, generation=2, evaluations_kept=3):
    """Return a copy of the bag ending after some evaluations of a generation."""
    messages = decoded_messages(real_run.mcap, topics.EVALUATIONS)
    of_generation = [m for m in messages if m.generation == generation]
    cut_id = of_generation[evaluations_kept - 1].candidate_id
    state = {'cut': False}

    def keep(topic, log_time, message):
        if state['cut']:
            return False
        if topic == topics.EVALUATIONS and message.candidate_id == cut_id:
            state['cut'] = True
        return True

    return copy_bag(real_run.mcap, path, keep=keep), {m.candidate_id for m in of_generation[
        :evaluations_kept]}


@pytest.mark.system
def test_resume_from_an_interrupted_bag_reaches_the_uninterrupted_result(real_run, tmp_path):
    bag, kept_ids = interrupted_copy(real_run, tmp_path / 'interrupted.mcap')
    point = resume_point(bag)
    assert point.batches_told == 2 and point.evaluations_told == 12
    assert set(point.known) == kept_ids
    assert len(point.to_evaluate) == 3
    assert 'resuming run' in point.describe()
    evaluated = []
    search = point.search
    while not search.stop():
        results = {}
        for candidate in search.ask():
            if candidate.candidate_id in point.known:
                results[candidate.candidate_id] = point.known[candidate.candidate_id]
            else:
                evaluated.append(candidate.candidate_id)
                results[candidate.candidate_id] = evaluate(candidate.x,
                                                           search.batch_task).objectives
        search.tell(results)
    assert len(evaluated) == 3 + 6      # the rest of generation 2, then generation 3
    result, structure = search.best
    expected = real_run.result
    assert result.candidate_id == expected['best_candidate_id']
    assert result.fitness == expected['fitness']
    assert result.objectives.tolist() == list(expected['objectives'].values())
    candidates = {c.candidate_id: c for c in decoded_messages(real_run.mcap, topics.CANDIDATES)}
    assert np.array_equal(result.x, candidates[result.candidate_id].genome)


@pytest.mark.system
def test_a_finished_run_is_not_resumed(real_run):
    with pytest.raises(UserError, match=r'already finished \(maxiter=4\); nothing to resume'):
        resume_point(real_run.bag)


@pytest.mark.system
def test_a_bag_that_disagrees_with_its_seed_is_refused(real_run, tmp_path):
    def other_seed(topic, message):
        if topic == topics.RUN_INFO:
            message.seed = 4
            return True
        return False

    bag = copy_bag(real_run.mcap, tmp_path / 'seed4.mcap', edit=other_seed)
    with pytest.raises(UserError, match='disagrees with a fresh search of its task and seed'):
        resume_point(bag)


@pytest.mark.system
def test_a_bag_without_run_info_cannot_be_resumed(real_run, tmp_path):
    bag = copy_bag(real_run.mcap, tmp_path / 'statuses.mcap',
                   keep=lambda topic, *_: topic == topics.EVALUATOR_STATUS)
    with pytest.raises(UserError, match='holds no RunInfo'):
        resume_point(bag)


@pytest.mark.system
def test_run_resume_after_interrupting_a_run(real_run, tmp_path):
    # The bag is cut in generation 2 as an interrupted recorder leaves it. (Interrupting a
    # live run of this size raced with its end: generations of 6 candidates on 2 worlds take
    # a tenth of a second, so the run sometimes finished before the signal arrived.)
    bag, _ = interrupted_copy(real_run, tmp_path / 'interrupted.mcap')
    resumed = tmp_path / 'resumed'
    finished = run_cli('run', '--resume', bag, '--evaluators', '2', '--bag', resumed,
                       '--domain-id', 'auto')
    assert finished.returncode == 0, finished.stdout + finished.stderr
    result = json.loads((resumed / 'result.json').read_text())
    for key in ('best_candidate_id', 'fitness', 'objectives', 'design'):
        assert result[key] == real_run.result[key], key


@pytest.mark.system
def test_a_finished_run_continues_as_a_run_of_the_larger_budget(real_run, tmp_path):
    # the real run had 4 generations; continued to 6, it ends where a 6-generation run of the
    # same task and seed ends, having evaluated only generations 4 and 5
    continued = tmp_path / 'continued'
    finished = run_cli('run', '--resume', real_run.bag, '--iterations', '6', '--evaluators',
                       '2', '--bag', continued, '--domain-id', 'auto')
    assert finished.returncode == 0, finished.stdout + finished.stderr
    assert '6 generations' in finished.stdout + finished.stderr
    longer = tmp_path / 'longer'
    budget = list(BUDGET)
    budget[budget.index('--iterations') + 1] = '6'
    run_codesign(longer, budget=budget)
    result = json.loads((continued / 'result.json').read_text())
    expected = json.loads((longer / 'result.json').read_text())
    for key in ('best_candidate_id', 'generation', 'fitness', 'objectives', 'design'):
        assert result[key] == expected[key], key
    assert result['stop_reason'] == 'maxiter=6'
    record = read_run(continued)
    assert record.run_info.iterations == 6
    assert record.run_info.resumed_from == read_run(real_run.bag).run_info.run_id
    assert sorted(set(np.asarray(record.candidates['generation']).tolist())) == [4, 5]


@pytest.mark.system
def test_a_continued_run_continues_again_with_the_bag_it_continued_beside_it(real_run, tmp_path):
    # a continued run's bag starts where the run it continued stopped (generation 4); resumed
    # again, the search is rebuilt from both bags, and without the first one the run is
    # refused in one line naming it, instead of starting over from generation 0
    shutil.copytree(real_run.bag, tmp_path / 'first')
    continued = tmp_path / 'continued'
    finished = run_cli('run', '--resume', tmp_path / 'first', '--iterations', '6',
                       '--evaluators', '2', '--bag', continued, '--domain-id', 'auto')
    assert finished.returncode == 0, finished.stdout + finished.stderr
    point = resume_point(continued, iterations=8)
    assert point.batches_told == 6 and point.evaluations_told == 36
    alone = tmp_path / 'alone'
    shutil.copytree(continued, alone / 'continued')
    first_run = read_run(real_run.bag).run_info.run_id
    with pytest.raises(UserError, match=f'run {first_run}, which this run continued'):
        resume_point(alone / 'continued', iterations=8)
    unused = tmp_path / 'unused'
    printed = run_cli('run', '--resume', alone / 'continued', '--iterations', '8', '--bag',
                      unused)
    assert printed.returncode != 0 and not unused.exists()
    assert first_run in printed.stderr and 'Traceback' not in printed.stderr


@pytest.mark.system
def test_continuing_asks_for_more_generations_than_the_run_had(real_run, tmp_path):
    with pytest.raises(UserError, match='continues to more generations than the 4 of'):
        resume_point(real_run.bag, iterations=4)
    unused = tmp_path / 'unused'
    printed = run_cli('run', '--resume', real_run.bag, '--iterations', '3', '--bag', unused)
    assert printed.returncode != 0 and not unused.exists()
    assert 'continues to more generations than the 4 of' in printed.stderr
    assert 'Traceback' not in printed.stderr


def resampled(task):
    return task.replace(worlds=dataclasses.replace(task.worlds, resample='generation'))


@pytest.mark.parametrize('preset, change, kind', [
    ('task4.yaml', None, 'a structure hierarchy'), ('task1.yaml', None, 'two stages'),
    ('task5.yaml', resampled, 'worlds resampled each generation'),
    ('task5.yaml', lambda task: task.replace(algorithm='bipop-cma'),
     r'with restarts \(bipop-cma\)')])
def test_only_a_run_of_one_optimizer_continues(preset, change, kind):
    task = load_run_task(ROOT / 'config' / 'tasks' / preset)
    with pytest.raises(UserError, match=f'searches {kind}, whose later batches depend'):
        extended_task(change(task) if change else task, task.iterations + 1, 'bags/run')
    if change:  # the same task with one optimizer continues
        assert extended_task(task, 250, 'bags/run').iterations == 250
