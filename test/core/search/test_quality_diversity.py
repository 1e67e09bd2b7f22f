"""CMA-MAE and CMA-ME: the archive, its descriptors, state, replay, task keys, a real run."""

import importlib.util
import json
import math
import os
import pathlib
import pickle
import subprocess
import sys

from analysis_run import copy_bag
from analysis_run import decoded_messages
from analysis_run import run_cli
from analysis_run import until_evaluation_of
from hand_codesign.analysis import records
from hand_codesign.bag.reader import read_run
from hand_codesign.cli import main
from hand_codesign.core import load_task
from hand_codesign.core.evaluate import evaluate
from hand_codesign.core.outcomes import Answer
from hand_codesign.core.search.factory import make_optimizer
from hand_codesign.core.search.optimizers import (AskTellOptimizer, Candidate, OptimizerError,
                                                  replay, TellError)
from hand_codesign.core.search.quality_diversity import CmaMae, CmaMe
from hand_codesign.core.task.descriptors import DESCRIPTORS, DesignDescriptors
from hand_codesign.core.task.genome import genome_spec
from hand_codesign.core.task.parts import DESCRIPTOR_NAMES
from layout import FOLDERS
import numpy as np
import pytest
from task_files import optimizer_document, write_task as write_task_file
from test_optimizers import run, same_candidates
from test_system import assert_same_with_two_evaluators, finish, start_run, summaries
import yaml

ROOT = pathlib.Path(__file__).resolve().parents[3]
# Where a fresh interpreter finds the tests and their helpers (test/helpers/layout.py).
TEST_DIRS = [str(folder) for folder in FOLDERS]
TASK5 = ROOT / 'config' / 'tasks' / 'task5.yaml'
QD = [CmaMae, CmaMe]


def sphere(x):
    """Return a shifted sphere on the normalized genome (minimum 0 at 0.3 in each coordinate)."""
    return np.array([float(np.sum((np.asarray(x) - 0.3) ** 2))])


@pytest.mark.parametrize('algorithm', QD)
def test_ask_tell_finds_better_designs_than_its_start_and_keeps_an_archive(algorithm):
    optimizer = algorithm(6, [1.0], population=20, iterations=25, seed=1)
    asked = run(optimizer, sphere)
    assert optimizer.batch_sizes == (10, 10)  # one emitter per 10 candidates
    assert len(asked) == 20 * 25 and [c.candidate_id for c in asked] == list(range(500))
    start = sphere(optimizer.x0)[0]
    assert optimizer.result.fitness < 0.2 * start  # CMA-ME explores more than it descends
    # the result is the lowest weighted sum ever told, and the archive's best elite
    values = [sphere(c.x)[0] for c in asked]
    assert optimizer.result.fitness == min(values)
    elites = optimizer.elites()
    assert elites[0].candidate_id == optimizer.result.candidate_id
    assert [e.fitness for e in elites] == sorted(e.fitness for e in elites)
    assert len(elites) >= 20 and len({e.cell for e in elites}) == len(elites)
    by_id = {c.candidate_id: c for c in asked}
    for elite in elites:
        # each elite is a design told, in the cell of its descriptors (the first two genes,
        # folded into [0, 1], for a bare optimizer), and the best told in that cell
        assert np.array_equal(elite.x, by_id[elite.candidate_id].x)
        assert elite.fitness == values[elite.candidate_id]
        assert elite.cell == tuple(min(int(v * 10), 9) for v in elite.descriptors)
    grid = optimizer.fitness_grid()
    assert grid.shape == (10, 10) and np.isfinite(grid).sum() == len(elites)


def test_cma_mae_thresholds_start_at_the_median_of_generation_0():
    optimizer = CmaMae(4, [1.0], population=8, iterations=3, seed=2)
    first = optimizer.ask()
    optimizer.tell({c.candidate_id: sphere(c.x) for c in first})
    median = np.median([-sphere(c.x)[0] for c in first])
    assert optimizer.threshold == pytest.approx(median) and optimizer.threshold < median
    # only designs at least as good as the median entered the annealed archive
    assert len(optimizer._scheduler.archive) <= 4 + 1
    assert CmaMe(4, [1.0], population=8, iterations=3, seed=2).learning_rate == 1.0


def test_emitters_share_the_population_and_refuse_too_many():
    assert CmaMae(4, [1.0], population=23, iterations=2, seed=0, emitters=3).batch_sizes == (
        8, 8, 7)
    assert CmaMae(4, [1.0], population=9, iterations=2, seed=0).batch_sizes == (9,)
    with pytest.raises(OptimizerError, match=r'emitters must be an integer from 1 to '
                                             r'population / 2 = 4'):
        CmaMae(4, [1.0], population=8, iterations=2, seed=0, emitters=5)
    with pytest.raises(OptimizerError, match='cells must be two positive integers'):
        CmaMe(4, [1.0], population=8, iterations=2, seed=0, cells=(0, 3))


CONTINUE = """
import pickle, sys
sys.path[:0] = {test_dirs!r}
from test_quality_diversity import sphere
from test_optimizers import run
from hand_codesign.core.search.optimizers import AskTellOptimizer
optimizer = AskTellOptimizer.from_state(open({state!r}, 'rb').read())
rows = [(c.candidate_id, c.generation, c.x) for c in run(optimizer, sphere)]
elites = [(e.candidate_id, e.cell, e.fitness) for e in optimizer.elites()]
pickle.dump((rows, elites), open({out!r}, 'wb'))
"""


@pytest.mark.system
@pytest.mark.parametrize('algorithm', QD)
def test_state_pickles_and_continues_bit_identically_also_in_another_process(algorithm,
                                                                             tmp_path):
    def fresh():
        return algorithm(5, [1.0], population=8, iterations=12, seed=4)

    reference = fresh()
    asked = run(reference, sphere)
    elites = [(e.candidate_id, e.cell, e.fitness) for e in reference.elites()]
    again = fresh()
    head = run(again, sphere, generations=5)
    between = again.get_state()
    pending = again.ask()
    in_flight = again.get_state()
    assert same_candidates(head + pending, asked[:len(head) + len(pending)])
    for state, start in ((between, len(head)), (in_flight, len(head))):
        restored = AskTellOptimizer.from_state(state)
        assert same_candidates(run(restored, sphere), asked[start:])
        assert [(e.candidate_id, e.cell, e.fitness) for e in restored.elites()] == elites
    (tmp_path / 'state').write_bytes(in_flight)
    script = CONTINUE.format(test_dirs=TEST_DIRS, state=str(tmp_path / 'state'),
                             out=str(tmp_path / 'out'))
    env = dict(os.environ, PYTHONHASHSEED='4321', PYTHONPATH=str(ROOT))
    subprocess.run([sys.executable, '-c', script], check=True, env=env, timeout=300)
    rows, continued_elites = pickle.loads((tmp_path / 'out').read_bytes())
    assert same_candidates([Candidate(*row) for row in rows], asked[len(head):])
    assert continued_elites == elites


@pytest.mark.parametrize('algorithm', QD)
def test_replay_rebuilds_the_archive_and_the_pending_generation(algorithm):
    original = algorithm(5, [1.0], population=8, iterations=20, seed=6)
    asked = run(original, sphere, generations=6)
    partial = original.ask()
    recorded = {c.candidate_id: sphere(c.x) for c in asked + partial[:3]}
    rebuilt = algorithm(5, [1.0], population=8, iterations=20, seed=6)
    assert replay(rebuilt, recorded, {c.candidate_id: c.x for c in asked + partial}) == 6
    assert same_candidates(rebuilt.pending, partial)
    assert [(e.candidate_id, e.cell) for e in rebuilt.elites()] == [
        (e.candidate_id, e.cell) for e in original.elites()]
    assert same_candidates(run(rebuilt, sphere), run(original, sphere))


def task_document(algorithm='cma-mae', archive=None):
    return optimizer_document(algorithm, archive=archive)


def write_task(folder, document, name='qd.yaml'):
    return write_task_file(folder, document, name)


def made_up_answer(x):
    """Return two objectives and a limit_rest share of a genome (any function will do)."""
    share = float(np.floor(np.asarray(x)[0] * 20 % 1.0 * 5) / 4)  # 0, 1/4, ... or 1
    return Answer.of([float(np.sum((np.asarray(x) - 0.3) ** 2)), 0.0], ('limit_rest',), [share])


def outcome_task(tmp_path):
    archive = {'descriptors': ['joint_range', 'limit_rest'], 'cells': [5, 4]}
    return load_task(write_task(tmp_path, task_document('cma-mae', archive)))


def test_an_archive_spans_outcomes_told_with_the_objectives(tmp_path):
    task = outcome_task(tmp_path)
    optimizer = make_optimizer(task.replace(population=8), genome_spec(task).size)
    assert optimizer.describe.names == ('joint_range', 'limit_rest')
    assert optimizer.ranges == ((0.0, pytest.approx(math.pi)), (0.0, 1.0))
    first = optimizer.ask()
    with pytest.raises(TellError, match=r'without the outcome descriptors \['
                                        r"'limit_rest'\]") as refused:
        optimizer.tell({c.candidate_id: made_up_answer(c.x).objectives for c in first})
    assert refused.value.invalid == [c.candidate_id for c in first]
    asked = run(optimizer, made_up_answer, generations=4)  # unchanged by the refusal
    assert same_candidates(asked[:8], first)
    by_id = {c.candidate_id: c for c in asked}
    spans = DesignDescriptors(task, ('joint_range',))
    for elite in optimizer.elites():
        x = by_id[elite.candidate_id].x
        assert elite.descriptors == (spans(x)[0], made_up_answer(x).outcomes[0])
    assert len({elite.cell[1] for elite in optimizer.elites()}) > 1
    rebuilt = make_optimizer(task.replace(population=8), genome_spec(task).size)
    answers = {c.candidate_id: made_up_answer(c.x) for c in asked}
    assert replay(rebuilt, answers, {c.candidate_id: c.x for c in asked}) == 4
    assert [(e.candidate_id, e.cell) for e in rebuilt.elites()] == [
        (e.candidate_id, e.cell) for e in optimizer.elites()]
    assert same_candidates(rebuilt.ask(), optimizer.ask())


def test_descriptors_of_task5_designs_and_their_default_ranges():
    task = load_task(TASK5).replace(algorithm='cma-mae')
    assert tuple(DESCRIPTORS) == DESCRIPTOR_NAMES
    describe = DesignDescriptors(task, ('finger_length', 'joint_range'))
    # four segments of 4 to 9 cm; each joint's two limit genes within [-pi/2, pi/2]
    assert describe.ranges == [(pytest.approx(0.16), pytest.approx(0.36)),
                               (0.0, pytest.approx(math.pi))]
    spec = genome_spec(task)
    x = np.random.default_rng(0).uniform(0, 1, spec.size)
    design = spec.decode(x)
    lengths = [length for finger in design.hand.fingers for length in finger.segment_lengths]
    spans = [joint.upper_limit - joint.lower_limit for finger in design.hand.fingers
             for joint in finger.joints]
    assert describe(x).tolist() == [pytest.approx(sum(lengths)), pytest.approx(np.mean(spans))]
    asymmetry = DesignDescriptors(task, ('length_asymmetry', 'initial_angle'))
    per_finger = [sum(finger.segment_lengths) for finger in design.hand.fingers]
    assert asymmetry(x)[0] == pytest.approx(abs(per_finger[0] - per_finger[1]))
    assert asymmetry.ranges[0] == (0.0, pytest.approx(0.10))


def test_tasks_select_cma_mae_and_cma_me_with_their_archive(tmp_path):
    archive = {'descriptors': ['joint_range', 'length_asymmetry'], 'cells': [6, 4],
               'ranges': [[0.5, 2.5], [0, 0.05]], 'emitters': 2, 'learning_rate': 0.1}
    task = load_task(write_task(tmp_path, task_document('cma-mae', archive)))
    optimizer = make_optimizer(task, genome_spec(task).size, first_id=5)
    assert type(optimizer) is CmaMae and optimizer.cells == (6, 4)
    assert optimizer.ranges == ((0.5, 2.5), (0.0, 0.05)) and optimizer.learning_rate == 0.1
    assert optimizer.batch_sizes == (40, 40) and optimizer.describe.names == (
        'joint_range', 'length_asymmetry')
    assert optimizer.ask()[0].candidate_id == 5
    task = load_task(write_task(tmp_path, task_document('cma-me')))
    optimizer = make_optimizer(task, genome_spec(task).size)
    assert type(optimizer) is CmaMe and optimizer.cells == (10, 10)
    assert optimizer.describe.names == ('finger_length', 'joint_range')
    assert len(optimizer.batch_sizes) == 8 and np.array_equal(optimizer.x0, np.full(
        genome_spec(task).size, 0.5))


def test_joints_without_limits_span_the_archive_by_their_initial_angles(tmp_path, capsys):
    free_joints = ROOT / 'config' / 'tasks' / 'task4_free_joints.yaml'
    task = load_task(free_joints).replace(algorithm='cma-mae')
    optimizer = make_optimizer(task, genome_spec(task).size)
    assert optimizer.describe.names == ('finger_length', 'initial_angle')
    assert optimizer.ranges == ((pytest.approx(0.03), pytest.approx(0.10)),
                                (pytest.approx(-math.pi / 2), pytest.approx(math.pi / 2)))
    document = yaml.safe_load(free_joints.read_text())
    document['optimizer'].update(algorithm='cma-me', archive={
        'descriptors': ['finger_length', 'joint_range']})
    path = write_task(tmp_path, document, 'limitless.yaml')
    assert main(['check', str(path)]) == 2
    err = capsys.readouterr().err
    assert err.strip() == (
        f'hand-codesign check: error: {path}: optimizer.archive.descriptors: expected '
        "descriptors the task has, got 'joint_range', which needs joint limits (finger0.joint0 "
        'has none: see morphology.joint_limits)')


def test_check_shows_the_archive_a_run_would_fill(tmp_path, capsys):
    path = write_task(tmp_path, task_document('cma-mae'))
    assert main(['check', str(path)]) == 0
    text = ' '.join(capsys.readouterr().out.split())
    assert ('archive: 10 x 10 cells over finger_length [0.16, 0.36] m x joint_range [0, 3.142] '
            'rad; 8 CMA-ES emitters of 10 candidates, learning rate 0.01') in text
    assert main(['check', str(TASK5), '--json']) == 0
    assert json.loads(capsys.readouterr().out)['budget']['archive'] is None


BAD_ARCHIVES = [
    ('cma-mae', {'cells': [0, 10]}, 'optimizer.archive.cells[0]: expected a positive integer, '
                                    'got 0'),
    ('cma-mae', {'descriptors': ['finger_length', 'wrist_angle']},
     'optimizer.archive.descriptors[1]: expected one of finger_length, length_asymmetry, '
     'joint_range, initial_angle, finger_spread, friction, limit_rest, touch, turn, got '
     "'wrist_angle'"),
    ('cma-mae', {'descriptors': ['finger_spread', 'joint_range']},
     'optimizer.archive.descriptors: expected descriptors that vary on structure [2, 2], got '
     "'finger_spread', which the task fixes at 0.14"),
    ('cma-mae', {'ranges': [[1, 0], [0, 1]]}, 'optimizer.archive.ranges[0]: expected lower '
                                              '<= upper'),
    ('cma-mae', {'emitters': 50}, 'optimizer.archive.emitters: expected at most population / '
                                  '2 = 40 emitters'),
    ('cma-me', {'learning_rate': 0.5}, 'optimizer.archive.learning_rate: expected no '
                                       'learning_rate for cma-me'),
    ('cma', {'cells': [5, 5]}, 'optimizer.archive: expected no archive for cma (it is for '
                               'cma-mae and cma-me'),
    ('mocma', {'descriptors': ['joint_range', 'limit_rest']},
     'optimizer.archive: expected no archive for mocma (it is for cma-mae and cma-me'),
    ('cma-mae', {'descriptors': ['limit_rests', 'joint_range']},
     'optimizer.archive.descriptors[0]: expected one of finger_length, length_asymmetry, '
     'joint_range, initial_angle, finger_spread, friction, limit_rest, touch, turn, got '
     "'limit_rests'"),
]


@pytest.mark.system
@pytest.mark.parametrize('algorithm,archive,expected', BAD_ARCHIVES)
def test_a_bad_archive_key_is_one_line_naming_file_and_key(algorithm, archive, expected,
                                                           tmp_path, capsys):
    path = write_task(tmp_path, task_document(algorithm, archive), 'wrong.yaml')
    assert main(['run', '--task', str(path), '--bag', str(tmp_path / 'bag'),
                 '--domain-id', 'auto']) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and 'Traceback' not in err
    assert f'{path}: {expected}' in err


BUDGET = ['--iterations', '3', '--population', '8', '--world-states', '2', '--seed', '3']


@pytest.fixture(scope='module')
def mae_run(tmp_path_factory):
    """Return (task, bag, output) of a real cma-mae run of Task 5 with one evaluator."""
    folder = tmp_path_factory.mktemp('mae')
    task = write_task(folder, task_document('cma-mae', {'cells': [5, 5]}))
    bag = folder / 'one'
    output = finish(start_run(bag, 1, budget=BUDGET, task=task))
    return task, bag, output


@pytest.mark.system
def test_a_real_cma_mae_run_reports_the_archives_recommended_design(mae_run):
    task, bag, output = mae_run
    result = json.loads((bag / 'result.json').read_text())
    assert result['evaluations'] == 24 and result['stop_reason'] == 'maxiter=3'
    assert f'best design: candidate {result["best_candidate_id"]}' in output
    record = read_run(bag, run_id=result['run_id'])
    evaluations = record.evaluations
    fitness = {int(i): float(np.dot([1.0, 0.1], o))
               for i, o in zip(evaluations['candidate_id'], evaluations['objectives'])}
    assert result['best_candidate_id'] == min(fitness, key=fitness.get)


@pytest.mark.system
def test_a_real_cma_mae_run_is_the_same_with_two_evaluators(mae_run, tmp_path):
    task, bag, _ = mae_run
    assert_same_with_two_evaluators(bag, task, tmp_path, BUDGET)


@pytest.mark.system
def test_analyze_draws_the_archive_and_lists_its_best_designs(mae_run, tmp_path, capsys):
    _, bag, _ = mae_run
    result = json.loads((bag / 'result.json').read_text())
    capsys.readouterr()
    out = tmp_path / 'report'
    assert main(['analyze', str(bag), '--out', str(out)]) == 0
    printed = capsys.readouterr().out
    lines = printed.splitlines()
    fact = next(line for line in lines if line.startswith('archive '))
    assert 'cells filled, over finger_length [0.16, 0.36] x joint_range [0, 3.142]' in fact
    header = lines.index(next(line for line in lines if line.startswith('archive: the ')))
    assert lines[header + 1].split() == ['candidate', 'generation', 'finger_length', '(m)',
                                         'joint_range', '(rad)', 'fitness']
    first = lines[header + 2].split()
    assert first[0] == str(result['best_candidate_id']) and first[-1] == 'recommended'
    assert float(first[-2]) == pytest.approx(result['fitness'], rel=1e-3)
    rows = (out / 'archive.csv').read_text().splitlines()
    assert rows[0] == ('candidate_id,generation,cell_finger_length,cell_joint_range,'
                       'finger_length,joint_range,fitness')
    elites = [row.split(',') for row in rows[1:]]
    assert 2 <= len(elites) <= 25 and elites[0][0] == str(result['best_candidate_id'])
    assert len({(row[2], row[3]) for row in elites}) == len(elites)  # one elite per cell
    image = (out / 'archive.png').read_bytes()
    assert image[:8] == b'\x89PNG\r\n\x1a\n' and len(image) > 10000
    assert '![archive.png](archive.png)' in (out / 'report.md').read_text()


def resume_interrupted_copy(bag, folder):
    """Resume a copy of a run's bag cut within generation 2; assert its result; return it."""
    mcap, = sorted(bag.glob('*.mcap'))
    interrupted = copy_bag(mcap, folder / 'interrupted.mcap', keep=until_evaluation_of(18))
    resumed = folder / 'resumed'
    finished = run_cli('run', '--resume', interrupted, '--evaluators', '2', '--bag', resumed,
                       '--domain-id', 'auto')
    assert finished.returncode == 0, finished.stdout + finished.stderr
    result = json.loads((resumed / 'result.json').read_text())
    expected = json.loads((bag / 'result.json').read_text())
    for key in ('best_candidate_id', 'fitness', 'objectives', 'design'):
        assert result[key] == expected[key], key
    return resumed


@pytest.mark.system
def test_an_interrupted_cma_mae_run_resumes_to_the_same_result(mae_run, tmp_path):
    _, bag, _ = mae_run
    resume_interrupted_copy(bag, tmp_path)


@pytest.fixture(scope='module')
def outcome_run(tmp_path_factory):
    """Return (task, bag) of a real cma-mae run over joint_range and limit_rest, 1 evaluator."""
    folder = tmp_path_factory.mktemp('outcomes')
    task = write_task(folder, task_document('cma-mae', {
        'descriptors': ['joint_range', 'limit_rest'], 'cells': [5, 3]}))
    bag = folder / 'one'
    finish(start_run(bag, 1, budget=BUDGET, task=task))
    return task, bag


def archive_elites(bag):
    """Return the elites of a run's archive replayed from its bag (records.archive_of)."""
    run_id = json.loads((bag / 'result.json').read_text())['run_id']
    archive = records.archive_of(read_run(bag, run_id=run_id))
    return [(e.candidate_id, e.cell, e.descriptors, e.fitness) for e in archive.elites()]


@pytest.mark.system
def test_a_real_run_spans_its_archive_by_outcomes_measured_in_its_evaluations(outcome_run):
    task_path, bag = outcome_run
    record = read_run(bag)
    evaluations = record.evaluations
    assert set(evaluations['outcome_names']) == {('limit_rest',)}
    shares = np.asarray(evaluations['outcomes'], dtype=float).ravel()
    assert len(shares) == 24 and set(shares) <= {0.0, 0.5, 1.0}  # 2 worlds per candidate
    task = records.run_task_of(record)
    genomes = dict(zip(record.candidates['candidate_id'].tolist(),
                       record.candidates['genome']))
    for row in range(0, 24, 7):  # the evaluator measured what core.evaluate measures
        evaluation = evaluate(genomes[int(evaluations['candidate_id'][row])], task)
        assert evaluation.outcomes.tolist() == [shares[row]]
    told = {int(i): s for i, s in zip(evaluations['candidate_id'], shares)}
    elites = archive_elites(bag)
    assert all(descriptors[1] == told[candidate_id]
               for candidate_id, _, descriptors, _ in elites)
    assert len({cell for _, cell, _, _ in elites}) == len(elites) >= 2
    decoded = decoded_messages(sorted(bag.glob('*.mcap'))[0], 'evaluations')
    assert [list(m.outcomes) for m in decoded] == [[s] for s in shares]


@pytest.mark.system
def test_a_real_run_with_outcomes_is_the_same_with_two_evaluators(outcome_run, tmp_path):
    task, bag = outcome_run
    assert_same_with_two_evaluators(bag, task, tmp_path, BUDGET)
    assert archive_elites(tmp_path / 'two') == archive_elites(bag)


@pytest.mark.system
def test_a_run_with_outcomes_resumes_from_its_bag_to_the_same_result(outcome_run, tmp_path):
    _, bag = outcome_run
    resumed = resume_interrupted_copy(bag, tmp_path)
    # the emitters, rebuilt with the recorded outcomes, asked what the uninterrupted run asked
    continued = summaries(resumed)
    assert continued and continued == summaries(bag)[-len(continued):]


@pytest.mark.system
def test_analyze_draws_an_archive_over_an_outcome(outcome_run, tmp_path, capsys):
    _, bag = outcome_run
    capsys.readouterr()
    out = tmp_path / 'report'
    assert main(['analyze', str(bag), '--out', str(out)]) == 0
    fact = next(line for line in capsys.readouterr().out.splitlines()
                if line.startswith('archive '))
    assert 'cells filled, over joint_range [0, 3.142] x limit_rest [0, 1]' in fact
    rows = (out / 'archive.csv').read_text().splitlines()
    assert rows[0] == ('candidate_id,generation,cell_joint_range,cell_limit_rest,joint_range,'
                       'limit_rest,fitness')
    assert len(rows) - 1 == len(archive_elites(bag))
    assert (out / 'archive.png').read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'


def test_without_pyribs_quality_diversity_is_refused_in_one_line(monkeypatch):
    found = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, 'find_spec',
                        lambda name, *rest: None if name == 'ribs' else found(name, *rest))
    with pytest.raises(OptimizerError) as raised:
        CmaMae(4, [1.0], 8, 3, seed=1)
    assert str(raised.value) == ('cma-mae needs pyribs, which is not installed: pip install '
                                 'ribs (pinned in requirements.txt, and in requirements-apt.txt '
                                 'for the apt path)')
