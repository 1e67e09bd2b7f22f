"""IPOP and BIPOP CMA-ES: restarts, growing populations, the budget, state, replay, a real run."""

import json
import os
import pathlib
import pickle
import subprocess
import sys

from hand_codesign.bag.reader import read_run
from hand_codesign.cli import main
from hand_codesign.core import load_task
from hand_codesign.core.search.factory import make_optimizer
from hand_codesign.core.search.optimizers import (AskTellOptimizer, Candidate, OptimizerError,
                                                  replay, ReplayError)
from hand_codesign.core.search.restarts import BipopCmaEs, IpopCmaEs
from hand_codesign.core.search.resume import rebuild_search
from hand_codesign.core.search.search import Search
from hand_codesign.core.task.genome import genome_spec
from layout import FOLDERS
import numpy as np
import pytest
from task_files import optimizer_document, write_task as write_task_file
from test_optimizers import run, same_candidates
from test_system import assert_same_with_two_evaluators, finish, start_run

ROOT = pathlib.Path(__file__).resolve().parents[3]
# Where a fresh interpreter finds the tests and their helpers (test/helpers/layout.py).
TEST_DIRS = [str(folder) for folder in FOLDERS]
TASK5 = ROOT / 'config' / 'tasks' / 'task5.yaml'
SHIFT = np.random.default_rng(0).uniform(-3.0, 3.0, 10)
RESTARTING = [IpopCmaEs, BipopCmaEs]


def rastrigin(x):
    """Rastrigin's function (minimum 0, a local minimum at every integer point) on [0, 1]^n."""
    y = 10.24 * (np.asarray(x) - 0.5) - SHIFT[:len(x)]
    return np.array([10.0 * len(y) + np.sum(y ** 2 - 10.0 * np.cos(2.0 * np.pi * y))])


def rugged(x):
    """Return a deterministic value without structure (its best improves ever more rarely)."""
    return np.array([np.modf(np.abs(np.sin(np.dot(x, np.arange(1.0, len(x) + 1)) * 1e4)))[0]])


def generation_sizes(asked):
    sizes = {}
    for candidate in asked:
        sizes[candidate.generation] = sizes.get(candidate.generation, 0) + 1
    return [sizes[generation] for generation in sorted(sizes)]


def test_ipop_restarts_with_doubled_populations_and_spends_exactly_its_budget():
    optimizer = IpopCmaEs(4, [1.0], population=6, iterations=1000, seed=1)
    asked = run(optimizer, rastrigin)
    restarts = optimizer.restarts
    assert len(restarts) >= 3
    assert [r.population for r in restarts] == [6 * 2 ** k for k in range(len(restarts))]
    assert [r.regime for r in restarts] == ['first'] + ['large'] * (len(restarts) - 1)
    assert all(r.reason for r in restarts[1:]) and all(r.sigma == 0.1 for r in restarts)
    # the first instance starts at the centre, every later one at a point of its own
    starts = [r.start for r in restarts]
    assert starts[0] == (0.5,) * 4 and len(set(starts)) == len(starts)
    assert all(0 <= value <= 1 for start in starts for value in start)
    assert optimizer.stop() == {'maxfevals': 6000, 'restarts': len(restarts) - 1}
    assert len(asked) == optimizer.evaluations == 6000
    assert [c.candidate_id for c in asked] == list(range(6000))
    sizes = generation_sizes(asked)
    assert [c.generation for c in asked] == sorted(c.generation for c in asked)
    for generation, size in enumerate(sizes[:-1]):  # the last one may be cut
        assert size == optimizer.restart_of(generation).population
    for restart in restarts:
        assert sum(sizes[:restart.generation]) == restart.evaluations
    assert optimizer.restart_of(len(sizes) - 1) == restarts[-1]
    # the best design is the lowest weighted sum ever told, across restarts
    values = [rastrigin(c.x)[0] for c in asked]
    assert optimizer.result.fitness == min(values)
    assert optimizer.result.candidate_id == int(np.argmin(values))
    with pytest.raises(OptimizerError, match='budget of 6000 evaluations is spent'):
        optimizer.ask()


def test_the_last_generation_is_cut_to_the_evaluations_left():
    optimizer = IpopCmaEs(4, [1.0], population=6, iterations=3, seed=2, stagnation=1)
    asked = run(optimizer, rugged)
    sizes = generation_sizes(asked)
    assert sum(sizes) == 18 and optimizer.stop()['maxfevals'] == 18
    # the restart after generation 1 doubled the population; 6 evaluations were left
    assert sizes == [6, 6, 6] and optimizer.restart_of(2).population == 12


def test_stagnation_ends_an_instance_after_the_window():
    optimizer = IpopCmaEs(3, [1.0], population=4, iterations=60, seed=3, stagnation=2)
    run(optimizer, rugged)
    stagnated = [r for r in optimizer.restarts if r.reason.startswith('stagnation')]
    assert stagnated and all(r.reason == 'stagnation: 2 generations without improvement'
                             for r in stagnated)
    default = IpopCmaEs(10, [1.0], population=10, iterations=5, seed=3)
    assert default.stagnation_window(10) == 2 * (10 + 30)
    assert default.stagnation_window(80) == 2 * (10 + 4)
    with pytest.raises(OptimizerError, match='stagnation must be an integer >= 1'):
        IpopCmaEs(3, [1.0], 4, 10, seed=0, stagnation=0)


def test_bipop_interleaves_small_runs_by_the_evaluations_of_each_regime():
    optimizer = BipopCmaEs(4, [1.0], population=6, iterations=2000, seed=4, stagnation=25)
    asked = run(optimizer, rastrigin)
    restarts = optimizer.restarts
    regimes = [r.regime for r in restarts]
    assert regimes[:2] == ['first', 'large'] and 'small' in regimes
    large = [r.population for r in restarts if r.regime == 'large']
    assert large == [6 * 2 ** (k + 1) for k in range(len(large))]
    for index, restart in enumerate(restarts[1:], start=1):
        before = restarts[:index]
        spent = {'small': 0, 'large': 0}
        for earlier, end in zip(before, [r.evaluations for r in before[1:]] +
                                [restart.evaluations]):
            spent['large' if earlier.regime == 'large' else 'small'] += end - earlier.evaluations
        expected = 'small' if spent['small'] < spent['large'] else 'large'
        assert restart.regime == expected, (index, spent)
        if restart.regime == 'small':
            latest = [r for r in before if r.regime == 'large'][-1]
            assert 6 <= restart.population <= latest.population
            assert 0.1 * 1e-2 <= restart.sigma <= 0.1
            ends = [r.evaluations for r in before[1:]] + [restart.evaluations]
            latest_spent = ends[before.index(latest)] - latest.evaluations
            assert restart.max_generations == max(1, latest_spent // 2 // restart.population)
    assert len(asked) == optimizer.evaluations == 12000
    assert sum(optimizer.regime_evaluations().values()) == 12000


def saved_states(optimizer, function, between=(), pending=()):
    """Drive an optimizer; return (asked, {generation: state}) saved at those generations."""
    asked, states = [], {}
    while not optimizer.stop():
        if optimizer.generation in between:
            states[optimizer.generation] = (len(asked), optimizer.get_state())
        candidates = optimizer.ask()
        if optimizer.generation in pending:
            states[-optimizer.generation] = (len(asked), optimizer.get_state())
        asked += candidates
        optimizer.tell({c.candidate_id: function(c.x) for c in candidates})
    return asked, states


CONTINUE = """
import pickle, sys
sys.path[:0] = {test_dirs!r}
from test_restarts import rugged
from test_optimizers import run
from hand_codesign.core.search.optimizers import AskTellOptimizer
optimizer = AskTellOptimizer.from_state(open({state!r}, 'rb').read())
rows = [(c.candidate_id, c.generation, c.x) for c in run(optimizer, rugged)]
pickle.dump(rows, open({out!r}, 'wb'))
"""


@pytest.mark.system
@pytest.mark.parametrize('algorithm', RESTARTING)
def test_state_saved_anywhere_continues_bit_identically_in_another_process(algorithm, tmp_path):
    def fresh():
        return algorithm(4, [1.0], population=4, iterations=60, seed=5, stagnation=3)

    reference = fresh()
    asked = run(reference, rugged)
    restarts = reference.restarts
    assert len(restarts) >= 3
    last = reference.generation - 1
    # between the generation that ended an instance and the next one's first; a restarted
    # instance's first generation pending; the budget's last (cut) generation pending
    again, states = saved_states(fresh(), rugged, between=(restarts[1].generation,),
                                 pending=(restarts[2].generation, last))
    assert same_candidates(again, asked) and len(states) == 3
    for start, state in states.values():
        assert same_candidates(run(AskTellOptimizer.from_state(state), rugged), asked[start:])
    start, state = states[-last]
    (tmp_path / 'state').write_bytes(state)
    script = CONTINUE.format(test_dirs=TEST_DIRS, state=str(tmp_path / 'state'),
                             out=str(tmp_path / 'out'))
    # another hash seed: pycma keys its sent solutions by hash(bytes)
    env = dict(os.environ, PYTHONHASHSEED='4321', PYTHONPATH=str(ROOT))
    subprocess.run([sys.executable, '-c', script], check=True, env=env, timeout=120)
    continued = [Candidate(*row) for row in pickle.loads((tmp_path / 'out').read_bytes())]
    assert same_candidates(continued, asked[start:])


@pytest.mark.parametrize('algorithm', RESTARTING)
def test_replay_rebuilds_a_run_across_its_restarts(algorithm):
    original = algorithm(4, [1.0], population=4, iterations=1000, seed=6, stagnation=3)
    asked = run(original, rugged, generations=40)
    assert len(original.restarts) >= 3
    partial = original.ask()
    recorded = {c.candidate_id: rugged(c.x) for c in asked + partial[:2]}
    genomes = {c.candidate_id: c.x for c in asked + partial}
    rebuilt = algorithm(4, [1.0], population=4, iterations=1000, seed=6, stagnation=3)
    assert replay(rebuilt, dict(reversed(list(recorded.items()))), genomes) == 40
    assert rebuilt.restarts == original.restarts
    assert same_candidates(rebuilt.pending, partial)
    assert same_candidates(run(rebuilt, rugged), run(original, rugged))
    other_seed = algorithm(4, [1.0], population=4, iterations=1000, seed=7, stagnation=3)
    with pytest.raises(ReplayError, match='recorded genome differs'):
        replay(other_seed, recorded, genomes)


def task_document(algorithm='ipop-cma', stagnation=1):
    return optimizer_document(algorithm, restart_stagnation=stagnation)


def write_task(tmp_path, document, name='restarting.yaml'):
    return write_task_file(tmp_path, document, name)


def test_tasks_select_the_restart_algorithms(tmp_path):
    for algorithm, kind in (('ipop-cma', IpopCmaEs), ('bipop-cma', BipopCmaEs)):
        task = load_task(write_task(tmp_path, task_document(algorithm, 7)))
        optimizer = make_optimizer(task, genome_spec(task).size, first_id=3)
        assert type(optimizer) is kind and optimizer.stagnation == 7
        assert optimizer.budget == task.iterations * task.population
        assert optimizer.ask()[0].candidate_id == 3
    task = load_task(write_task(tmp_path, task_document('bipop-cma', None)))
    assert task.restart_stagnation is None
    assert make_optimizer(task, genome_spec(task).size).stagnation is None


@pytest.mark.system
def test_a_wrong_algorithm_is_one_line_naming_file_and_key(tmp_path, capsys):
    path = write_task(tmp_path, task_document('ipop', None), 'wrong.yaml')
    assert main(['run', '--task', str(path), '--bag', str(tmp_path / 'bag'),
                 '--domain-id', 'auto']) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and 'Traceback' not in err
    expected = 'expected one of cma, mocma, ipop-cma, bipop-cma, cma-mae, cma-me, got '
    assert f"{path}: optimizer.algorithm: {expected}'ipop'" in err


def fake_objectives(x):
    """Two objectives of a genome without physics, for runs of a real task's search."""
    return np.array([rugged(x)[0], float(np.sum((x - 0.3) ** 2))])


def test_a_restart_run_of_a_task_resumes_from_its_record():
    task = load_task(TASK5).replace(algorithm='ipop-cma', iterations=12, population=4,
                                    restart_stagnation=1)
    search = Search(task)
    asked = []
    while not search.stop():
        batch = search.ask()
        asked += batch
        search.tell({c.candidate_id: fake_objectives(c.x) for c in batch})
    assert len(search.optimizer.restarts) >= 2 and len(asked) == 48
    cut = asked[25].generation   # interrupted in the middle of a restart's generation
    seen = [c for c in asked if c.generation <= cut]
    recorded = {c.candidate_id: fake_objectives(c.x) for c in seen[:-1]}
    point = rebuild_search(task, 'run-1', 'test', recorded, {c.candidate_id: c.x for c in seen})
    assert set(point.known) == {c.candidate_id for c in seen[:-1] if c.generation == cut}
    assert [c.candidate_id for c in point.to_evaluate] == [seen[-1].candidate_id]
    rest = []
    while not point.search.stop():
        batch = point.search.ask()
        rest += batch
        point.search.tell({c.candidate_id: fake_objectives(c.x) for c in batch})
    assert same_candidates(rest, [c for c in asked if c.generation >= cut])
    assert point.search.best[0].candidate_id == search.best[0].candidate_id


BUDGET = ['--iterations', '4', '--population', '4', '--world-states', '2', '--seed', '3']


@pytest.fixture(scope='module')
def ipop_run(tmp_path_factory):
    """Return (task, bag, output) of a real ipop-cma run of Task 5: one evaluator, 16 evals."""
    folder = tmp_path_factory.mktemp('ipop')
    task = write_task(folder, task_document('ipop-cma', 1))
    bag = folder / 'one'
    output = finish(start_run(bag, 1, budget=BUDGET, task=task))
    return task, bag, output


@pytest.mark.system
def test_a_real_ipop_run_restarts_and_spends_its_budget(ipop_run, tmp_path, capsys):
    _, bag, output = ipop_run
    result = json.loads((bag / 'result.json').read_text())
    assert result['evaluations'] == 16
    assert result['stop_reason'].startswith('maxfevals=16, restarts=')
    assert int(result['stop_reason'].rsplit('=', 1)[1]) >= 1
    table = read_run(bag, run_id=result['run_id']).generation_summaries
    told = [len(ids) for ids, final in zip(table['told_ids'], table['final']) if not final]
    assert sum(told) == 16 and max(told) >= 8, told
    assert list(table['generation'][:len(told)]) == list(range(len(told)))
    assert '(restart 1, population 8;' in output and '/16 evaluations)' in output
    # the report replays the search to show where the restarts happened
    capsys.readouterr()
    assert main(['analyze', str(bag), '--out', str(tmp_path / 'report')]) == 0
    line = next(line for line in capsys.readouterr().out.splitlines()
                if line.startswith('restarts'))
    assert 'generation 0: population 4; generation ' in line and ': population 8, ' in line
    assert '(after stagnation: 1 generation without improvement)' in line


@pytest.mark.system
def test_a_real_ipop_run_is_the_same_with_two_evaluators(ipop_run, tmp_path):
    task, bag, _ = ipop_run
    assert_same_with_two_evaluators(bag, task, tmp_path, BUDGET)


@pytest.mark.system
def test_the_best_design_of_a_real_ipop_run_replays_bit_identically(ipop_run, capsys):
    _, bag, _ = ipop_run
    best = json.loads((bag / 'result.json').read_text())['best_candidate_id']
    capsys.readouterr()
    assert main(['replay', str(bag), '--gif', str(bag.parent / 'best.gif')]) == 0
    printed = capsys.readouterr().out
    assert f'replaying candidate {best} ' in printed
    assert 'replay reproduces the recorded objectives bit for bit' in printed
