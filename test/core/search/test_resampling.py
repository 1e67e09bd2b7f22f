"""Worlds resampled each generation, and the final check that chooses the run's design."""

import json
import pathlib
import subprocess
import sys

from analysis_run import copy_bag
from analysis_run import run_cli
from analysis_run import until_evaluation_of
from hand_codesign.analysis.records import best_candidate_id
from hand_codesign.analysis.records import design_task
from hand_codesign.analysis.records import open_run
from hand_codesign.analysis.records import recorded_design
from hand_codesign.analysis.resume import resume_point
from hand_codesign.bag.reader import read_run
from hand_codesign.cli import main
from hand_codesign.core.evaluate import evaluate
from hand_codesign.core.run.runs import load_run_task
from hand_codesign.core.search.optimizers import replay
from hand_codesign.core.search.resume import rebuild_search
from hand_codesign.core.search.search import Search
from hand_codesign.core.sim.worlds import world_states
from hand_codesign.errors import UserError
import numpy as np
import pytest
import yaml

ROOT = pathlib.Path(__file__).resolve().parents[3]
TASK5 = ROOT / 'config' / 'tasks' / 'task5.yaml'
CLI = [sys.executable, '-m', 'hand_codesign.cli']


def resampled_file(folder, final_check=2):
    document = yaml.safe_load(TASK5.read_text())
    document['worlds'] = {'resample': 'generation', 'final_check': final_check}
    path = folder / 'task5_resampled.yaml'
    path.write_text(yaml.safe_dump(document, sort_keys=False))
    return path


@pytest.fixture(scope='module')
def task_file(tmp_path_factory):
    return resampled_file(tmp_path_factory.mktemp('tasks'))


def synthetic(candidates, task):
    """Objectives of the genome plus an offset of the worlds: each draw is easier than the last."""
    offset = 0.0 if task.world_draw == 0 else 1.0 / task.world_draw
    return {c.candidate_id: np.array([float(np.sum((c.x - 0.3) ** 2)) + offset, 0.5])
            for c in candidates}


def run_to_end(search, evaluate_batch=synthetic):
    recorded, genomes, batches = {}, {}, []
    while not search.stop():
        batch = search.ask()
        assert all(c.variant.world_draw == search.batch_task.world_draw for c in batch)
        results = evaluate_batch(batch, search.batch_task)
        recorded.update(results)
        genomes.update({c.candidate_id: c.x.copy() for c in batch})
        batches.append((batch, search.checking))
        search.tell(results)
    return recorded, genomes, batches


def test_each_generation_meets_its_own_draw_and_the_final_check_the_fixed_worlds(task_file):
    task = load_run_task(task_file, 3, 4, 5, 2)
    search = Search(task)
    recorded, _, batches = run_to_end(search)
    generations = [batch for batch, checking in batches if not checking]
    assert [batch[0].variant.world_draw for batch in generations] == [1, 2, 3, 4]
    assert [[c.generation for c in batch] for batch in generations] == [[g] * 5 for g in range(4)]
    (check, checking), = [entry for entry in batches if entry[1]]
    # the best candidate (on its own draw) of each of the last two generations, again
    bests = [min(batch, key=lambda c: recorded[c.candidate_id][0]) for batch in generations]
    assert [c.variant.world_draw for c in check] == [0, 0] and checking
    assert [c.candidate_id for c in check] == [20, 21]
    for repeated, best in zip(check, bests[-2:]):
        assert np.array_equal(repeated.x, best.x)
    # the result is the better on the fixed worlds: not the lowest fitness ever told, which
    # is the last generation's only because its draw is the easiest
    result, _ = search.best
    winner = min(check, key=lambda c: recorded[c.candidate_id][0])
    assert result.candidate_id == winner.candidate_id
    assert np.array_equal(result.objectives, recorded[winner.candidate_id])
    assert search.optimizer.result.candidate_id != result.candidate_id
    assert search.stop() == {'maxiter': 4, 'final_check': 2}
    assert [design.check_id for design in search.final_check] == [20, 21]
    assert search.final_check[0].draw_fitness == pytest.approx(
        search.optimizer.fitness_of(recorded[bests[-2].candidate_id]))
    # one fresh draw per generation: four sets of worlds, none the fixed one
    draws = [world_states(task.replace(world_draw=k)) for k in (1, 2, 3, 4)]
    assert all(draw != world_states(task) for draw in draws)
    assert len({tuple(draw) for draw in draws}) == 4


def test_a_run_shorter_than_its_final_check_checks_every_generation(task_file):
    task = load_run_task(task_file, 3, 1, 4, 2)
    search = Search(task)
    _, _, batches = run_to_end(search)
    assert [len(batch) for batch, _ in batches] == [4, 1]
    assert search.stop() == {'maxiter': 1, 'final_check': 1}


def same_result(first, second):
    return (first.candidate_id == second.candidate_id and np.array_equal(first.x, second.x)
            and first.objectives.tobytes() == second.objectives.tobytes())


def test_resume_and_replay_rebuild_the_resampled_run_and_its_check(task_file):
    task = load_run_task(task_file, 5, 3, 4, 2)
    whole = Search(task)
    recorded, genomes, batches = run_to_end(whole)
    again = Search(task)
    assert replay(again, recorded, genomes) == len(batches) == 4
    assert again.stop() == whole.stop() and same_result(again.best[0], whole.best[0])
    # interrupted in generation 1, then in the final check
    for cut in (6, 13):
        kept = {i: v for i, v in recorded.items() if i < cut}
        point = rebuild_search(task, 'r', 'test', kept, genomes)
        resumed = point.search
        while not resumed.stop():
            batch = resumed.ask()
            for candidate in batch:
                assert np.array_equal(candidate.x, genomes[candidate.candidate_id])
            resumed.tell(synthetic(batch, resumed.batch_task))
        assert same_result(resumed.best[0], whole.best[0]), cut
    with pytest.raises(UserError, match='already finished'):
        rebuild_search(task, 'r', 'test', recorded, genomes)


# ---------------------------------------------------------------- a real run


def real_run(bag, evaluators, task_file):
    command = CLI + ['run', '--task', str(task_file), '--evaluators', str(evaluators),
                     '--bag', str(bag), '--iterations', '3', '--population', '4',
                     '--world-states', '2', '--seed', '4', '--domain-id', 'auto']
    process = subprocess.run(command, cwd=ROOT, stdout=subprocess.PIPE,
                             stderr=subprocess.STDOUT, text=True, timeout=300)
    assert process.returncode == 0, process.stdout
    return process.stdout


@pytest.fixture(scope='module')
def runs(tmp_path_factory, task_file):
    folder = tmp_path_factory.mktemp('resampled_runs')
    outputs = {count: real_run(folder / f'evaluators{count}', count, task_file)
               for count in (1, 2)}
    return folder, outputs


def summaries(bag):
    table = read_run(bag).generation_summaries
    fields = ['generation', 'check', 'told_ids', 'told_objectives', 'best_candidate_id',
              'best_objectives', 'best_fitness', 'best_genome', 'final']
    return [{name: np.asarray(table[name][row]).tolist() for name in fields}
            for row in range(len(table))]


@pytest.mark.system
def test_a_real_resampled_run_is_the_same_with_one_and_two_evaluators(runs):
    folder, outputs = runs
    one, two = folder / 'evaluators1', folder / 'evaluators2'
    assert 'final check on the fixed worlds' in outputs[1]
    result = json.loads((one / 'result.json').read_text())
    best, = [entry for entry in result['final_check']
             if entry['candidate_id'] == result['best_candidate_id']]
    assert (f'best design: candidate {best["candidate_id"]} of the final check (candidate '
            f'{best["repeats"]} of generation {best["generation"]} on the fixed worlds), '
            f'fitness') in outputs[1]
    assert summaries(one) == summaries(two)
    results = [json.loads((bag / 'result.json').read_text()) for bag in (one, two)]
    for key in ('best_candidate_id', 'fitness', 'objectives', 'design', 'final_check',
                'stop_reason'):
        assert results[0][key] == results[1][key], key
    assert len(set(read_run(two).evaluations['evaluator_id'])) == 2


@pytest.mark.system
def test_the_reported_design_is_the_final_checks_best_on_the_fixed_worlds(runs, capsys,
                                                                          tmp_path):
    bag = runs[0] / 'evaluators2'
    result = json.loads((bag / 'result.json').read_text())
    assert result['stop_reason'] == 'maxiter=3, final_check=2'
    record = read_run(bag)
    candidates = record.candidates
    draw = {int(i): int(d) for i, d in zip(candidates['candidate_id'], candidates['world_draw'])}
    assert [draw[i] for i in range(14)] == [1] * 4 + [2] * 4 + [3] * 4 + [0, 0]
    checked = result['final_check']
    assert [entry['candidate_id'] for entry in checked] == [12, 13]
    assert [entry['generation'] for entry in checked] == [1, 2]
    best = min(checked, key=lambda entry: entry['fitness'])   # the first on ties
    assert result['best_candidate_id'] == best['candidate_id']
    assert result['fitness'] == best['fitness']
    # analysis and replay take the same design, evaluated on the run's fixed worlds
    opened = open_run(bag, warn=False)
    assert best_candidate_id(opened) == best['candidate_id']
    design = recorded_design(opened, best['candidate_id'])
    task = design_task(opened, design)
    assert design.world_draw == 0 and world_states(task) == world_states(
        task.replace(world_draw=0))
    repeated = recorded_design(opened, best['repeats'])
    assert repeated.world_draw == best['generation'] + 1
    assert np.array_equal(design.x, repeated.x)
    assert evaluate(design.x, task).objectives.tolist() == list(result['objectives'].values())
    capsys.readouterr()
    assert main(['replay', str(bag)]) == 0
    printed = capsys.readouterr().out
    assert f'replaying candidate {best["candidate_id"]} ' in printed
    assert 'replay reproduces the recorded objectives bit for bit' in printed
    assert main(['analyze', str(bag), '--out', str(tmp_path / 'report')]) == 0
    report = (tmp_path / 'report' / 'report.md').read_text()
    assert 'a fresh draw per generation, then a final check of 2 designs on the fixed' in report
    assert (f'Candidate {best["candidate_id"]} of generation 3, its final check on the fixed '
            'worlds') in ' '.join(report.split())
    with pytest.raises(UserError, match=r'already finished \(maxiter=3, final_check=2\)'):
        resume_point(bag)


@pytest.mark.system
def test_a_resampled_run_resumed_in_its_final_check_reports_the_same_design(runs, tmp_path):
    bag = runs[0] / 'evaluators2'
    mcap, = sorted(bag.glob('*.mcap'))
    # the bag ends at the first answer of the check
    interrupted = copy_bag(mcap, tmp_path / 'interrupted.mcap',
                           keep=until_evaluation_of(12))
    point = resume_point(interrupted)
    assert point.search.checking and len(point.known) == 1 and len(point.to_evaluate) == 1
    resumed = tmp_path / 'resumed'
    finished = run_cli('run', '--resume', interrupted, '--evaluators', '2', '--bag', resumed,
                       '--domain-id', 'auto')
    assert finished.returncode == 0, finished.stdout + finished.stderr
    result = json.loads((resumed / 'result.json').read_text())
    expected = json.loads((bag / 'result.json').read_text())
    for key in ('best_candidate_id', 'fitness', 'objectives', 'design', 'final_check'):
        assert result[key] == expected[key], key
