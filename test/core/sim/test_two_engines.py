"""
Physics as a randomized quantity (issue 47): a task evaluated in both engines on the same worlds.

The task file's `physics.engines` and `physics.engine_aggregate`, read and refused; an
evaluation in both engines against its two single-engine evaluations (mean and worst); the
evaluator's refusal of an engine it cannot import; a two-engine `hand-codesign run` end to end,
its RunInfo listing both engines, its export re-simulated in both, bit-identical with 1 and 2
evaluators and after an evaluator is SIGKILLed; `analyze --unseen` reporting each engine, and
`transfer` reading it.
"""

import dataclasses
import json
import pathlib

from analysis_run import run_cli
from hand_codesign.bag.reader import read_run
from hand_codesign.core.evaluate import across_engines, evaluate
from hand_codesign.core.run import evaluation_jobs
from hand_codesign.core.run.evaluation_jobs import CandidateRejected, check_engine
from hand_codesign.core.run.preview import preview
from hand_codesign.core.run.runs import engines_version
from hand_codesign.core.task import parse_task, TaskError
from hand_codesign.core.task.genome import genome_spec
import numpy as np
import pytest
from test_system import finish, run_killing_an_evaluator, start_run, summaries
import yaml

TASK = pathlib.Path(__file__).resolve().parents[3] / 'config' / 'tasks' / 'task5.yaml'
BOTH = ['--engine', 'pybullet,mujoco']
GENERATIONS = 4
BUDGET = ['--iterations', str(GENERATIONS), '--population', '6', '--world-states', '4',
          '--seed', '7']


def task_with(physics, **changes):
    """Return task5 with the given physics mapping (and other top-level keys), parsed."""
    document = yaml.safe_load(TASK.read_text())
    document['physics'] = physics
    document.update(changes)
    return parse_task(yaml.safe_dump(document), source='two.yaml')


def test_the_task_reads_a_list_of_engines_and_engine_alone_as_before():
    task = task_with({'engines': ['pybullet', 'mujoco']})
    assert task.physics.engines == ('pybullet', 'mujoco')
    assert (task.physics.engine, task.physics.engine_aggregate) == ('pybullet', 'mean')
    worst = task_with({'engines': ['mujoco', 'pybullet'], 'engine_aggregate': 'worst'})
    assert (worst.physics.engine, worst.physics.engine_aggregate) == ('mujoco', 'worst')
    alone = task_with({'engine': 'mujoco'})
    assert (alone.physics.engine, alone.physics.engines) == ('mujoco', ('mujoco',))
    assert task_with({}).physics.engines == ('pybullet',)
    # code that sets engine alone, as before the list, gets that one engine
    assert dataclasses.replace(task.physics, engine='mujoco').engines == ('mujoco',)
    assert dataclasses.replace(alone.physics, engine='pybullet').engines == ('pybullet',)


@pytest.mark.parametrize('physics, message', [
    ({'engines': ['pybullet', 'ode']}, 'two.yaml: physics.engines: expected a non-empty list '
     "of distinct engines of pybullet, mujoco, e.g. [pybullet, mujoco], got ['pybullet', 'ode']"),
    ({'engines': []}, 'two.yaml: physics.engines: expected a non-empty list'),
    ({'engines': ['mujoco', 'mujoco']}, 'two.yaml: physics.engines: expected a non-empty list'),
    ({'engines': 'pybullet'}, 'two.yaml: physics.engines: expected a non-empty list'),
    ({'engine': 'mujoco', 'engines': ['mujoco']}, 'two.yaml: physics.engine: expected engine '
     'or engines, not both'),
    ({'engines': ['pybullet', 'mujoco'], 'engine_aggregate': 'median'},
     "two.yaml: physics.engine_aggregate: expected one of mean, worst, got 'median'"),
])
def test_a_bad_engine_list_is_one_line_naming_the_key(physics, message):
    with pytest.raises(TaskError) as refused:
        task_with(physics)
    assert str(refused.value).startswith(message)
    assert '\n' not in str(refused.value)


def test_racing_with_several_engines_is_refused_at_load():
    with pytest.raises(TaskError) as refused:
        task_with({'engines': ['pybullet', 'mujoco']}, worlds={'racing': {}})
    assert str(refused.value).startswith('two.yaml: worlds.racing: expected no racing with '
                                         'several physics.engines')
    assert '\n' not in str(refused.value)


@pytest.mark.parametrize('aggregate', ['mean', 'worst'])
def test_two_engines_score_the_aggregate_of_the_two_single_engine_evaluations(aggregate):
    task = task_with({'engines': ['pybullet', 'mujoco'], 'engine_aggregate': aggregate},
                     world_states=2)
    x = np.full(genome_spec(task).size, 0.5)  # the bounds' centres: no start collision
    both = evaluate(x, task)
    each = [evaluate(x, task.replace(physics=task.physics.with_engines((name,))))
            for name in ('pybullet', 'mujoco')]
    stacked = np.array([evaluation.objectives for evaluation in each])
    expected = stacked.mean(axis=0) if aggregate == 'mean' else stacked.max(axis=0)
    assert not both.collision and not np.array_equal(*stacked)  # the engines do differ
    np.testing.assert_array_equal(both.objectives, expected)
    assert both.fitness == float(expected @ task.objective_weights)
    for name in ('world_objectives', 'initial_errors', 'final_errors', 'final_poses'):
        np.testing.assert_array_equal(getattr(both, name),  # engine by engine
                                      np.concatenate([getattr(e, name) for e in each]))
    assert both.simulated_time == sum(e.simulated_time for e in each)
    again = across_engines(task, each)
    np.testing.assert_array_equal(again.objectives, both.objectives)


def test_the_preview_counts_each_engine_s_rollouts():
    two = {'engines': ['pybullet', 'mujoco']}
    one, both = (preview(task_with(physics)) for physics in ({}, two))
    assert both['steps_per_evaluation'] == 2 * one['steps_per_evaluation']
    assert both['budget']['rollouts'] == 2 * one['budget']['rollouts']


def test_engine_alone_evaluates_bit_identically_to_a_list_of_it():
    task = task_with({'engine': 'pybullet'}, world_states=2)
    listed = task_with({'engines': ['pybullet']}, world_states=2)
    x = np.full(genome_spec(task).size, 0.5)
    np.testing.assert_array_equal(evaluate(x, task).objectives, evaluate(x, listed).objectives)


class _Run:
    run_id = 'run-1'
    engine = 'pybullet,mujoco'
    engine_version = engines_version('pybullet,mujoco')


def test_an_evaluator_that_cannot_import_an_engine_refuses_the_run_in_one_line(monkeypatch):
    check_engine(_Run())  # this process has both
    real = evaluation_jobs.importlib.util.find_spec
    monkeypatch.setattr(evaluation_jobs.importlib.util, 'find_spec',
                        lambda name: None if name == 'mujoco' else real(name))
    with pytest.raises(CandidateRejected) as refused:
        check_engine(_Run())
    assert str(refused.value) == ('run run-1 simulates with pybullet,mujoco; this evaluator '
                                  'cannot import mujoco: install it or start the evaluator '
                                  'where it is')


@pytest.fixture(scope='module')
def two_engine_run(tmp_path_factory):
    bag = tmp_path_factory.mktemp('engines') / 'two'
    finish(start_run(bag, 2, extra=BOTH, budget=BUDGET, task=TASK))
    return bag


@pytest.mark.system
def test_a_two_engine_run_lists_both_engines_and_any_process_recomputes_it(two_engine_run,
                                                                           tmp_path):
    record = read_run(two_engine_run)
    info = record.run_info
    assert info.engine == 'pybullet,mujoco'
    assert info.engine_version == engines_version('pybullet,mujoco')
    assert info.engine_version.startswith('pybullet==') and ',mujoco==' in info.engine_version
    task = info.task()
    assert task.physics.engines == ('pybullet', 'mujoco')
    row = record.evaluations.row(len(record.evaluations) - 1)
    genome = next(np.asarray(record.candidates.row(index)['genome'], dtype=float)
                  for index in range(len(record.candidates))
                  if record.candidates.row(index)['candidate_id'] == row['candidate_id'])
    np.testing.assert_array_equal(np.asarray(row['objectives']), evaluate(genome, task).objectives)
    exported = run_cli('export', two_engine_run, '--out', tmp_path / 'export')
    assert exported.returncode == 0, exported.stdout  # 0: re-simulated in both, same bits


@pytest.mark.system
def test_a_two_engine_run_is_the_same_with_one_evaluator_and_after_a_kill(two_engine_run,
                                                                          tmp_path):
    one = tmp_path / 'one'
    finish(start_run(one, 1, extra=BOTH, budget=BUDGET, task=TASK))
    assert summaries(one) == summaries(two_engine_run)
    killed = tmp_path / 'killed'
    run_killing_an_evaluator(killed, BUDGET, extra=BOTH, after=f'generation 1/{GENERATIONS}')
    assert summaries(killed) == summaries(two_engine_run)


@pytest.mark.system
def test_analyze_unseen_reports_each_engine_and_transfer_tabulates_it(two_engine_run, tmp_path):
    report = tmp_path / 'report'
    measured = run_cli('analyze', two_engine_run, '--unseen', '2', '--out', report)
    assert measured.returncode == 0, measured.stderr
    assert '| error | within, pybullet | within, mujoco |' in measured.stdout
    unseen = json.loads((report / 'unseen.json').read_text())
    assert unseen['run_engine'] == 'pybullet,mujoco'
    assert sorted(unseen['engines']) == ['mujoco', 'pybullet']
    assert all(unseen['engines'][name]['engine'] == name for name in unseen['engines'])
    folder = tmp_path / 'transfer'
    folder.mkdir()
    (folder / 'seed7-in-both.json').write_text((report / 'unseen.json').read_text())
    tabled = run_cli('transfer', folder, '--title', 'Task 5 in both engines')
    assert tabled.returncode == 0, tabled.stderr
    table = (tmp_path / 'transfer.md').read_text()
    assert '| seed7 | both |' in table and 'found in both: there is PyBullet' in table


@pytest.mark.system
def test_run_refuses_an_unknown_engine_in_one_line():
    refused = run_cli('run', '--task', TASK, '--engine', 'pybullet,ode')
    assert refused.returncode == 2
    assert refused.stderr.strip().splitlines()[-1].endswith(
        'expected pybullet or mujoco, or several comma-separated, e.g. pybullet,mujoco; got '
        "'pybullet,ode'")
