"""A run's search one batch at a time: the same view of a single optimization and a hierarchy."""

import pathlib

from hand_codesign.core.run.runs import load_run_task
from hand_codesign.core.search.search import Search
from hand_codesign.core.sim.objectives import weighted_fitness
from hand_codesign.core.task.genome import genome_spec
import numpy as np

TASKS = pathlib.Path(__file__).resolve().parents[3] / 'config' / 'tasks'


def objectives(candidates, size):
    return {c.candidate_id: np.full(size, float(np.sum(c.x ** 2))) for c in candidates}


def test_ask_repeats_the_batch_until_it_is_told():
    task = load_run_task(TASKS / 'task5.yaml', 7, 2, 4, 2)
    search = Search(task)
    first = search.ask()
    assert [c.candidate_id for c in search.ask()] == [c.candidate_id for c in first]
    assert all(c.variant.structure == task.structure for c in first)
    assert all(c.x.shape == (genome_spec(task).size,) for c in first)
    search.tell(objectives(first, len(task.objective_names)))
    second = search.ask()
    assert [c.candidate_id for c in second] == [4, 5, 6, 7]
    assert {c.generation for c in second} == {1}
    assert not search.hierarchical and not search.checking and search.batch_task is task


def test_a_search_stops_after_its_budget_with_the_best_design():
    task = load_run_task(TASKS / 'task5.yaml', 7, 2, 4, 2)
    search = Search(task)
    assert search.best is None
    told = {}
    while not search.stop():
        results = objectives(search.ask(), len(task.objective_names))
        told.update(results)
        search.tell(results)
    assert search.stop() == {'maxiter': 2}
    result, structure = search.best
    assert structure == task.structure
    assert result.fitness == min(weighted_fitness(value, task.objective_weights)
                                 for value in told.values())


def test_a_same_seed_gives_the_same_candidates():
    task = load_run_task(TASKS / 'task5.yaml', 7, 2, 4, 2)
    one, two = Search(task).ask(), Search(task).ask()
    assert all(np.array_equal(a.x, b.x) for a, b in zip(one, two))
    other = Search(task.replace(seed=8)).ask()
    assert not np.array_equal(one[0].x, other[0].x)


def test_a_hierarchy_checks_each_structure_on_its_evaluation_worlds():
    task = load_run_task(TASKS / 'task4.yaml', 3, 1, 4, 2)
    search = Search(task)
    assert search.hierarchical
    seen = []
    while not search.stop():
        batch = search.ask()
        seen.append((search.checking, batch[0].variant.structure,
                     search.batch_task.num_world_states, batch[0].variant.held_out))
        size = len(task.objective_names)
        search.tell(objectives(batch, size))
    # the structure is optimized twice, then its best design is checked on held-out worlds
    assert seen[:2] == [(False, (1,), 2, False)] * 2
    assert seen[2] == (True, (1,), task.hierarchy.evaluation_world_states, True)
    assert seen[3][:2] == (False, (2,))
    _, structure = search.best
    assert structure in {entry[1] for entry in seen}
