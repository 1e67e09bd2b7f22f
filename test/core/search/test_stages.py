"""Two stages in one run (Tasks 1 and 2): the nominal world first, then the randomized worlds."""

import json
import pathlib
import types

from analysis_run import run_codesign
from hand_codesign.analysis.records import design_task
from hand_codesign.analysis.records import recorded_design
from hand_codesign.bag.reader import read_run
from hand_codesign.cli import main
from hand_codesign.core.evaluate import evaluate
from hand_codesign.core.run.evaluation_jobs import candidate_task
from hand_codesign.core.run.runs import load_run_task
from hand_codesign.core.search.optimizers import replay
from hand_codesign.core.search.resume import rebuild_search
from hand_codesign.core.search.search import Search
from hand_codesign.core.sim.worlds import world_states, WorldState
from hand_codesign.core.task import TaskError
import numpy as np
import pytest

TASKS = pathlib.Path(__file__).resolve().parents[3] / 'config' / 'tasks'


def two_stage(name, seed=5, iterations=2, population=4, worlds=3):
    task = load_run_task(TASKS / name, seed, iterations, population, worlds)
    return task.replace(two_stage=True)


def synthetic(candidates, size):
    """Objectives that depend on the genome and the stage, without simulating."""
    return {c.candidate_id: np.full(size, float(np.sum((c.x - 0.3) ** 2)) + c.variant.stage)
            for c in candidates}


def run_to_end(task, evaluate_batch):
    search = Search(task)
    recorded, genomes, batches = {}, {}, []
    while not search.stop():
        batch = search.ask()
        results = evaluate_batch(search.batch_task, batch)
        recorded.update(results)
        genomes.update({c.candidate_id: c.x.copy() for c in batch})
        batches.append(batch)
        search.tell(results)
    return search, recorded, genomes, batches


def test_stage_one_uses_the_nominal_world_and_stage_two_starts_from_its_result():
    task = two_stage('task1.yaml')
    size = len(task.objective_names)
    search, _, _, batches = run_to_end(task, lambda _, batch: synthetic(batch, size))
    stages = [batch[0].variant.stage for batch in batches]
    assert stages == [1] * task.iterations + [2] * task.iterations
    assert [c.candidate_id for batch in batches for c in batch] == list(
        range(2 * task.iterations * task.population))
    assert world_states(task.replace(stage=1)) == [WorldState.nominal()]
    assert world_states(task.replace(stage=2)) == world_states(task)
    driver = search._driver
    # stage 2's optimizer started at stage 1's best design, with its own seed
    assert np.array_equal(driver.optimizer.x0, driver.stage_results[1].x)
    assert driver.seeds[1] == task.seed and driver.seeds[2] != task.seed
    assert search.stop() == {'stage': 2, 'maxiter': task.iterations}
    best, _ = search.best
    assert best.candidate_id >= task.iterations * task.population  # a stage-2 design


def test_a_two_stage_run_resumes_and_replays_bit_identically():
    task = two_stage('task2.yaml', iterations=2, population=4)  # with its growing horizon
    size = len(task.objective_names)
    whole, recorded, genomes, batches = run_to_end(
        task, lambda _, batch: synthetic(batch, size))
    # interrupted in the middle of stage 2's first generation
    cut = batches[task.iterations][0].candidate_id + 2
    kept = {i: v for i, v in recorded.items() if i < cut}
    point = rebuild_search(task, 'r', 'test', kept, genomes)
    assert point.search.stage == 2 and sorted(point.known) == [cut - 2, cut - 1]
    assert [c.candidate_id for c in point.to_evaluate] == list(
        range(cut, batches[task.iterations][-1].candidate_id + 1))
    resumed = point.search
    while not resumed.stop():
        batch = resumed.ask()
        for candidate in batch:
            assert np.array_equal(candidate.x, genomes[candidate.candidate_id])
        resumed.tell(synthetic(batch, size))
    assert resumed.best[0].candidate_id == whole.best[0].candidate_id
    assert np.array_equal(resumed.best[0].x, whole.best[0].x)
    again = Search(task)
    assert replay(again, recorded, genomes) == len(batches)
    assert again.stop() == whole.stop() and np.array_equal(again.best[0].x, whole.best[0].x)
    assert again.horizons == whole.horizons


def test_real_evaluations_of_each_stage_are_what_an_evaluator_computes():
    task = two_stage('task1.yaml', iterations=1, population=4, worlds=2)

    def real(batch_task, batch):
        return {c.candidate_id: evaluate(c.x, batch_task) for c in batch}

    search, recorded, _, batches = run_to_end(task, real)
    assert [len(recorded[c.candidate_id].world_objectives) for c in batches[0]] == [1] * 4
    assert [len(recorded[c.candidate_id].world_objectives) for c in batches[1]] == [2] * 4
    # an evaluator rebuilds each candidate's task from the run's RunInfo and the message
    run = types.SimpleNamespace(
        run_id='r', task_yaml=task.source_text, seed=task.seed,
        iterations=1, population=4, world_states=2)
    for batch in batches:
        candidate = batch[0]
        message = types.SimpleNamespace(
            run_id='r', structure=[], world_states=0, horizon=candidate.variant.horizon,
            stage=candidate.variant.stage, held_out_worlds=False)
        rebuilt, _ = candidate_task(run, message)
        assert np.array_equal(evaluate(candidate.x, rebuilt).objectives,
                              recorded[candidate.candidate_id].objectives)


def test_two_stages_and_a_hierarchy_do_not_combine():
    task = load_run_task(TASKS / 'task4.yaml')
    with pytest.raises(TaskError, match='two_stage: expected no two stages'):
        task.replace(two_stage=True)


@pytest.mark.system
def test_a_real_two_stage_run_is_recorded_replayed_and_analyzed(tmp_path):
    task_file = TASKS / 'task1.yaml'
    assert load_run_task(task_file).two_stage  # the paper's two stages
    bag = tmp_path / 'two_stage'
    output = run_codesign(bag, ['--iterations', '2', '--population', '4', '--world-states', '2',
                                '--seed', '2'], task=task_file)
    assert 'generation 2/2 of stage 1' in output and 'generation 2/2 of stage 2' in output
    record = read_run(bag)
    candidates = record.candidates
    stage_of = dict(zip(candidates['candidate_id'], candidates['stage']))
    assert [stage_of[i] for i in range(16)] == [1] * 8 + [2] * 8
    worlds = {int(row['candidate_id']): len(row['world_objectives']) // 8
              for row in (record.evaluations.row(i) for i in range(len(record.evaluations)))}
    assert [worlds[i] for i in range(16)] == [1] * 8 + [2] * 8  # 8 objectives per world
    result = json.loads((bag / 'result.json').read_text())
    assert result['best_candidate_id'] >= 8 and result['stop_reason'] == 'stage=2, maxiter=2'
    # analyze and replay rebuild each candidate's task with its stage (records.design_task)
    stage_one = recorded_design(record, 3)
    assert stage_one.stage == 1
    rebuilt = design_task(record, stage_one)
    assert np.array_equal(evaluate(stage_one.x, rebuilt).objectives, stage_one.objectives)
    assert main(['analyze', str(bag), '--out', str(tmp_path / 'report')]) == 0
    rows = (tmp_path / 'report' / 'generations.csv').read_text().splitlines()
    assert rows[0].endswith(',stage') and [row[-1] for row in rows[1:]] == list('1122')
    assert 'of stage 2 (the randomized worlds)' in (tmp_path / 'report' / 'report.md').read_text()
