"""The hand-structure hierarchy: Fig. 1's structures, the bottom-up order and the stop rule."""

import dataclasses
import pathlib

from hand_codesign.core.evaluate import evaluate
from hand_codesign.core.search.hierarchy import (all_structures, bottom_up_path,
                                                 evaluate_candidates, HierarchyError,
                                                 HierarchySearch, run_hierarchy, transitions)
from hand_codesign.core.search.optimizers import replay, TellError
from hand_codesign.core.sim.worlds import world_states
from hand_codesign.core.task import load_task, parse_task
import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]
TASK5 = ROOT / 'config' / 'tasks' / 'task5.yaml'

HIERARCHY = """
hierarchy:
  start: {start}
  stop_structure: [2, 3]
  position_threshold: 0.004
  orientation_threshold: 0.11
  evaluation_world_states: 32
"""


def hierarchy_task(start=(1,), iterations=3, population=4, algorithm='cma'):
    """Return Task 5 searched over structures, with an orientation goal added."""
    text = TASK5.read_text()
    text = text.replace('  orientation: []\n', '  orientation:\n    - {time: 1.5, orientation: '
                        '[0, 0, 0, 1], trajectory: false}\n')
    text = text.replace('algorithm: cma', f'algorithm: {algorithm}')
    text += HIERARCHY.format(start=list(start))
    task = parse_task(text, source=str(TASK5))
    return task.replace(iterations=iterations, population=population)


class StructureDependentErrors:
    """
    A cheap stand-in for the simulator, to test the search logic only.

    The position error shrinks with the number of joints and the orientation error with the
    number of fingers: with the thresholds of HIERARCHY the first structure to meet both is
    (1, 2). It records the tasks it was called with.
    """

    def __init__(self):
        self.calls = []

    def __call__(self, task, candidates):
        self.calls.append((task.structure, task.num_world_states, len(candidates),
                           task.held_out))
        results = {}
        for candidate in candidates:
            distance = float(np.mean((candidate.x - 0.6) ** 2))
            joints, fingers = sum(task.structure), len(task.structure)
            results[candidate.candidate_id] = np.array(
                [0.01 / joints * (1 + distance), 0.2 / fingers * (1 + distance)])
        return results


def test_structures_of_fig1_in_documented_order():
    assert all_structures() == [
        (1,), (2,), (1, 1), (3,), (1, 2), (1, 1, 1), (2, 2), (1, 3), (1, 1, 2), (2, 3),
        (1, 2, 2), (1, 1, 3), (3, 3), (2, 2, 2), (1, 2, 3), (1, 3, 3), (2, 2, 3), (2, 3, 3),
        (3, 3, 3)]
    assert all_structures(max_fingers=2, max_joints=2) == [(1,), (2,), (1, 1), (1, 2), (2, 2)]


def test_transitions_add_remove_or_move_one_joint():
    assert transitions((1, 2)) == {
        (2, 2): 'add joint', (1, 3): 'add joint', (2,): 'remove finger', (1, 1, 2): 'add finger',
        (1, 1): 'remove joint', (3,): 'move joint', (1, 1, 1): 'move joint'}
    assert transitions((2,), max_fingers=1) == {(3,): 'add joint', (1,): 'remove joint'}


def test_bottom_up_path_tries_moves_before_additions():
    path = bottom_up_path((1,), stop=(2, 3))
    assert path == [(1,), (2,), (1, 1), (1, 2), (3,), (1, 3), (2, 2), (2, 3)]
    for before, after in zip(path, path[1:]):
        kind = transitions(before, 2, 3)[after]
        assert kind in ('move joint', 'add joint', 'add finger')
        moves = [s for s, k in transitions(before, 2, 3).items() if k == 'move joint']
        if kind != 'move joint':  # an addition only once every move leads somewhere visited
            assert all(s in path[:path.index(before)] for s in moves)
    assert bottom_up_path((2, 1), stop=(3, 3)) == [(1, 2), (3,), (1, 3), (2, 2), (2, 3), (3, 3)]
    assert bottom_up_path((1,), max_fingers=2, max_joints=2) == [
        (1,), (2,), (1, 1), (1, 2), (2, 2)]
    with pytest.raises(HierarchyError, match=r'stop structure \[3, 3\] is not on the'):
        bottom_up_path((1,), stop=(3, 3), max_joints=2)


def test_search_stops_at_the_first_structure_meeting_the_thresholds():
    evaluate_batch = StructureDependentErrors()
    search = run_hierarchy(hierarchy_task(), evaluate_batch)

    assert search.stop() == {'goals_met': (1, 2)}
    assert [o.structure for o in search.outcomes] == [(1,), (2,), (1, 1), (1, 2)]
    assert [o.goals_met for o in search.outcomes] == [False, False, False, True]
    final = search.result
    assert final.structure == (1, 2)
    assert final.check_objectives[0] <= 0.004 and final.check_objectives[1] <= 0.11
    # Per structure: twice 3 generations of 4 on the task's worlds, then one check on 32 worlds.
    assert evaluate_batch.calls == [
        call for structure in [(1,), (2,), (1, 1), (1, 2)]
        for call in [(structure, 8, 4, False)] * 6 + [(structure, 32, 1, True)]]
    # Ids run on across structures; the check evaluates the better optimization's best design.
    assert [o.check_id for o in search.outcomes] == [24, 49, 74, 99]
    for outcome in search.outcomes:
        assert len(outcome.results) == 2 and len(set(outcome.seeds)) == 2
        assert outcome.result is min(outcome.results, key=lambda r: r.fitness)
        assert outcome.results[0].candidate_id < outcome.check_id - 12 <= \
            outcome.results[1].candidate_id < outcome.check_id
    seeds = [seed for outcome in search.outcomes for seed in outcome.seeds]
    assert len(set(seeds)) == len(seeds) and hierarchy_task().seed not in seeds


def test_three_finger_hands_grow_from_the_best_two_finger_hands():
    task = load_task(ROOT / 'config' / 'tasks' / 'task4.yaml')
    task = task.replace(iterations=1, population=4, hierarchy=dataclasses.replace(
        task.hierarchy, position_threshold=0.0))
    scores = {(1, 3): 0.1, (2, 2): 0.3, (1, 2): 0.2, (2, 3): 0.5, (1, 1): 0.9}

    def errors(batch_task, candidates):  # the check of (1, 3) and (1, 2) score best
        base = scores.get(batch_task.structure, 1.0)
        return {c.candidate_id: np.full(2, base + float(np.sum(c.x ** 2)) * 1e-3)
                for c in candidates}

    search = run_hierarchy(task, errors)
    visited = [o.structure for o in search.outcomes]
    assert visited == [(1,), (2,), (1, 1), (1, 2), (3,), (1, 3), (2, 2), (2, 3),
                       (1, 1, 3), (1, 1, 2)]
    assert search.stop() == {'path_end': (1, 1, 2)}
    scores[(1, 2)] = 0.4  # now (2, 2) is the second best two-finger hand
    assert [o.structure for o in run_hierarchy(task, errors).outcomes][-2:] == [
        (1, 1, 3), (1, 2, 2)]


def test_search_runs_the_whole_path_when_no_structure_is_good_enough():
    task = hierarchy_task(start=(2, 2), algorithm='mocma')
    task = task.replace(hierarchy=dataclasses.replace(task.hierarchy, position_threshold=0.0))
    search = run_hierarchy(task, StructureDependentErrors())
    assert search.stop() == {'path_end': (2, 3)}
    assert [o.structure for o in search.outcomes] == [(2, 2), (1, 3), (2, 3)]  # move first
    assert search.result.structure == (2, 3)  # the lowest weighted sum on the check worlds
    assert len(search.outcomes[0].result.pareto_ids) >= 1


def test_search_is_restored_and_replayed_exactly():
    evaluate_batch = StructureDependentErrors()
    task = hierarchy_task()
    reference = HierarchySearch(task)
    recorded = {}
    while len(reference.outcomes) < 2 or reference.checking:
        candidates = reference.ask()
        results = evaluate_batch(reference.evaluation_task, candidates)
        recorded.update(results)
        reference.tell(results)
    saved = reference.get_state()
    restored = HierarchySearch.from_state(saved)
    rebuilt = HierarchySearch(task)
    assert replay(rebuilt, recorded) == 14  # 2 structures of twice 3 generations and a check
    for search in (reference, restored, rebuilt):
        run_hierarchy(task, evaluate_batch, search)
    for search in (restored, rebuilt):
        assert search.stop() == reference.stop()
        assert [o.check_id for o in search.outcomes] == [o.check_id for o in reference.outcomes]
        assert np.array_equal(search.result.result.x, reference.result.result.x)


def test_check_tell_refuses_other_ids():
    search = HierarchySearch(hierarchy_task())
    while not search.checking:
        search.tell(StructureDependentErrors()(search.evaluation_task, search.ask()))
    (check,) = search.ask()
    assert search.evaluation_task.num_world_states == 32
    with pytest.raises(TellError, match=f'expects exactly id {check.candidate_id}'):
        search.tell({check.candidate_id + 1: [0.0, 0.0]})
    with pytest.raises(TellError, match='needs 2 finite objective values'):
        search.tell({check.candidate_id: [0.0]})


def test_task4_preset_visits_one_and_three_joints_before_growing_a_third_finger():
    task = load_task(ROOT / 'config' / 'tasks' / 'task4.yaml')
    search = HierarchySearch(task)
    assert search.path == [(1,), (2,), (1, 1), (1, 2), (3,), (1, 3), (2, 2), (2, 3)]
    assert search.structure_task.structure == (1,)


def test_stop_rule_on_real_evaluations_of_task4():
    task = load_task(ROOT / 'config' / 'tasks' / 'task4.yaml')
    loose = dataclasses.replace(task.hierarchy, evaluation_world_states=3,
                                position_threshold=0.05, orientation_threshold=1.0)
    task = task.replace(iterations=2, population=4, num_world_states=2, hierarchy=loose)
    for orientation_threshold, expected_stop in ((1.0, {'goals_met': (1,)}),
                                                 (0.1, {'path_end': (2,)})):
        task = task.replace(hierarchy=dataclasses.replace(
            loose, orientation_threshold=orientation_threshold))
        search = run_hierarchy(task, evaluate_candidates,
                               HierarchySearch(task, path=[(1,), (2,)]))
        assert search.stop() == expected_stop
        for outcome in search.outcomes:
            check_task = task.replace(structure=outcome.structure, num_world_states=3,
                                      held_out=True)
            evaluation = evaluate(outcome.result.x, check_task)
            assert np.array_equal(outcome.check_objectives, evaluation.objectives)
            training = world_states(task.replace(num_world_states=64))
            assert not set(world_states(check_task)) & set(training)
            within = (evaluation.objectives[0] <= 0.05 and
                      evaluation.objectives[1] <= orientation_threshold)
            assert outcome.goals_met == bool(within)
