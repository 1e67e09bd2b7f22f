"""Racing over the worlds: the race's bound, CMA-ES's treatment and raced runs without ROS."""

import dataclasses
import pathlib
import types

from hand_codesign.analysis.records import with_worlds
from hand_codesign.core.evaluate import evaluate, torque_penalty_of
from hand_codesign.core.run.controller import RunController
from hand_codesign.core.run.runs import load_run_task
from hand_codesign.core.search.optimizers import CmaEs
from hand_codesign.core.search.racing import (Race, RacedAnswer, round_bounds, RoundAnswer,
                                              serfling_radius)
from hand_codesign.core.search.resume import rebuild_search
from hand_codesign.core.sim.objectives import COLLISION_PENALTY, combine_worlds
from hand_codesign.core.task import RacingSpec
from hand_codesign.core.task.genome import genome_spec
from hand_codesign.core.task.parts import WorldsSpec
import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]
TASKS = ROOT / 'config' / 'tasks'
RUN = 'run-1'
WEIGHTS = np.array([1.0, 0.1])


def race_of(values, selected, spec, penalties=None):
    """Run a race on per-world values (candidates, worlds, objectives); return the Race."""
    count, worlds = values.shape[:2]
    race = Race(range(count), worlds, selected, spec, WEIGHTS, penalties or {})
    while not race.done:
        first, end = race.share
        race.told({i: RoundAnswer(combine_worlds(values[i, first:end]), values[i, first:end],
                                  False) for i in race.racing})
    return race


def test_rounds_split_the_worlds_evenly_and_no_round_is_empty():
    assert round_bounds(64, 4) == (0, 16, 32, 48, 64)
    assert round_bounds(10, 3) == (0, 3, 6, 10)
    assert round_bounds(2, 4) == (0, 1, 2)
    assert round_bounds(1, 4) == (0, 1)


def test_the_bound_shrinks_with_the_worlds_met_and_vanishes_with_all():
    radii = [serfling_radius(seen, 64, 0.1, 1e-3) for seen in (1, 16, 32, 48, 63, 64)]
    assert all(a > b for a, b in zip(radii, radii[1:]))
    assert radii[-1] == 0.0
    # Hoeffding for sampling with replacement, without Serfling's factor, is wider
    assert radii[1] < 0.1 * np.sqrt(np.log(2 / 1e-3) / 32)


def test_a_stopped_candidate_is_never_selected_whatever_the_bound_allows():
    # the decision itself: at the round a candidate stopped, let every final fitness be
    # anywhere within the bound around its fitness so far; it still ranks below mu others
    generator = np.random.default_rng(5)
    spec, stopped_any = RacingSpec(rounds=4, value_range=0.05, delta=0.05), 0
    for _ in range(30):
        centre = generator.uniform(0.0, 0.04, (20, 1, 1))
        values = centre + generator.uniform(0, 0.005, (20, 16, 2))
        race = Race(range(20), 16, 10, spec, WEIGHTS, {})
        while not race.done:
            first, end = race.share
            racing = race.racing
            race.told({i: RoundAnswer(combine_worlds(values[i, first:end]),
                                      values[i, first:end], False) for i in racing})
            radius = serfling_radius(end, 16, spec.value_range, race.delta)
            fitness = {i: race.fitness(i) for i in racing}
            for loser in set(racing) & race.stopped:
                worst_case = fitness[loser] - radius  # as good as the bound lets it be
                others = [fitness[i] + radius for i in racing if i != loser]
                assert sum(other < worst_case for other in others) >= 10
                stopped_any += 1
    assert stopped_any > 0


def test_stopped_candidates_are_not_the_best_mu_when_worlds_keep_to_the_range():
    # worlds drawn within the stated range: over many generations no stopped candidate
    # belongs to the mu best on all the worlds (delta bounds the chance per generation)
    generator = np.random.default_rng(11)
    spec = RacingSpec(rounds=4, value_range=0.04, delta=0.05)
    saved = wrong = 0
    for _ in range(200):
        centre = generator.uniform(0.0, 0.03, (30, 1, 1))
        values = np.clip(centre + generator.uniform(-0.005, 0.005, (30, 32, 2)), 0, 0.04 / 1.1)
        race = race_of(values, 15, spec)
        fitness = values.mean(axis=1) @ WEIGHTS
        best = set(np.argsort(fitness, kind='stable')[:15].tolist())
        wrong += len(best & race.stopped)
        saved += race.rollouts_saved()
    assert wrong == 0
    assert saved > 0  # it stops some: those whose first worlds are far behind


def test_complete_answers_are_the_whole_evaluation_bit_for_bit():
    task = load_run_task(TASKS / 'task5.yaml', 7, 2, 6, 4)
    spec = genome_spec(task)
    generator = np.random.default_rng(2)
    x = next(x for x in (np.clip(spec.initial_mean() + 0.1 * generator.normal(size=spec.size),
                                 0, 1) for _ in range(30)) if not evaluate(x, task).collision)
    whole = evaluate(x, task)
    race = Race([0], 4, 1, RacingSpec(rounds=2), task.objective_weights,
                {0: torque_penalty_of(x, task)})
    while not race.done:
        part = evaluate(x, task, share=race.share)
        assert part.world_objectives.shape == (2, 2) and not part.collision
        race.told({0: RoundAnswer(part.objectives, part.world_objectives, part.collision)})
    answer = race.answers()[0]
    assert answer.complete and answer.worlds == 4
    assert answer.objectives.tobytes() == whole.objectives.tobytes()


def test_a_design_that_collides_in_a_later_share_collides_in_the_first():
    task = load_run_task(TASKS / 'task5.yaml', 7, 2, 6, 8)
    spec = genome_spec(task)
    generator = np.random.default_rng(3)
    for _ in range(200):
        x = generator.random(spec.size)
        if evaluate(x, task).collision:
            break
    part = evaluate(x, task, share=(0, 1))
    assert part.collision and part.simulated_time == 0.0
    race = Race([0, 1], 8, 1, RacingSpec(rounds=4), WEIGHTS, {})
    race.told({0: RoundAnswer(part.objectives, part.world_objectives, True),
               1: RoundAnswer(np.zeros(2), np.zeros((2, 2)), False)})
    assert race.racing == [1]   # known at once: no further rounds
    race.told({1: RoundAnswer(np.zeros(2), np.zeros((2, 2)), False)})
    race.told({1: RoundAnswer(np.zeros(2), np.zeros((2, 2)), False)})
    race.told({1: RoundAnswer(np.zeros(2), np.zeros((2, 2)), False)})
    answer = race.answers()[0]
    assert answer.complete and list(answer.objectives) == [COLLISION_PENALTY] * 2


def cma(raced):
    return CmaEs(4, WEIGHTS, 8, 10, seed=3, raced=raced)


def test_raced_cma_es_moves_only_by_the_ranks_that_are_known():
    told = []
    for stopped_values in ((0.5, 0.9, 0.7, 0.6), (3.0, 0.8, 2.0, 5.0)):
        optimizer = cma(raced=True)
        batch = optimizer.ask()
        results = {}
        for index, candidate in enumerate(batch):
            if index < 4:   # complete: their fitness decides the update
                results[candidate.candidate_id] = RacedAnswer(np.array([0.1 * index, 0.0]), 8)
            else:           # stopped early, in another order each time
                results[candidate.candidate_id] = RacedAnswer(
                    np.array([stopped_values[index - 4], 0.0]), 2, complete=False)
        optimizer.tell(results)
        told.append([candidate.x for candidate in optimizer.ask()])
        assert optimizer.result.candidate_id == batch[0].candidate_id
    assert all(np.array_equal(a, b) for a, b in zip(*told))
    assert cma(raced=True)._es.opts['CMA_active'] is False
    assert cma(raced=True).selected == 4


def raced_task(rounds=4, value_range=0.01, iterations=3, population=12, worlds=8):
    task = load_run_task(TASKS / 'task5.yaml', 7, iterations, population, worlds)
    return task.replace(worlds=WorldsSpec(racing=RacingSpec(rounds, value_range)))


def world_values(x, first, end):
    """Return cheap per-world objectives (worlds, 2) of a genome: far apart between designs."""
    x = np.asarray(x, dtype=float)
    base = np.sum((x - 0.3) ** 2)
    worlds = np.arange(first, end)[:, None]
    wobble = 0.002 * np.sin(worlds * 1.7 + 10 * x[:2][None, :])
    return np.abs(np.array([0.2 * base, 0.5 * base]) + wobble)


def answer(controller, task, candidate, evaluator, attempt, shift=0.0):
    first, end = candidate.share
    values = world_values(candidate.x, first, end) + shift
    objectives = combine_worlds(values, torque_penalty_of(candidate.x, task))
    evaluation = types.SimpleNamespace(attempt=attempt, world_objectives=values.ravel(),
                                       collision=False)
    controller.evaluated(RUN, candidate.candidate_id, evaluator, objectives, 0.5,
                         evaluation=evaluation)


class Outbox:
    """What the controller sends, kept in order."""

    def __init__(self):
        self.sent, self.summaries, self.result = [], [], None

    def send_candidate(self, candidate, evaluator_id, attempt, genome_names, design):
        self.sent.append((candidate, evaluator_id, attempt))

    def send_summary(self, summary):
        self.summaries.append(summary)

    def log(self, text, level='info'):
        pass

    def finish(self, result):
        self.result = result


def raced_run(task, evaluators, order=None, silent=None, resumed=None, stale=False):
    """Drive a raced run to its end; return the Outbox. silent: an evaluator that stops."""
    clock = types.SimpleNamespace(now=100.0)
    outbox = Outbox()
    controller = RunController(task, RUN, outbox, resumed=resumed, clock=lambda: clock.now,
                               evaluators_expected=len(evaluators))
    alive = list(evaluators)
    for evaluator in alive:
        controller.heard_from(evaluator, 2)
    controller.tick()
    answered, rounds_seen = [], set()
    while outbox.result is None:
        sent, outbox.sent = outbox.sent, []
        if not sent:   # only a silent evaluator's candidates are left: they move on
            clock.now += 10.0
            for evaluator in alive:
                controller.heard_from(evaluator, 2)
            controller.tick()
            continue
        if order is not None:
            sent = [sent[index] for index in order(len(sent))]
        for candidate, evaluator, attempt in sent:
            rounds_seen.add(candidate.share)
            if evaluator == silent and len(answered) > 20:
                alive = [other for other in alive if other != silent]
                continue
            if stale and answered and answered[0][0].share != candidate.share:
                old, old_evaluator, old_attempt = answered[0]
                answer(controller, task, old, old_evaluator, old_attempt, shift=1.0)
            clock.now += 0.5
            answer(controller, task, candidate, evaluator, attempt)
            answered.append((candidate, evaluator, attempt))
            for evaluator_id in alive:
                controller.heard_from(evaluator_id, 2)
    assert len(rounds_seen) > 1
    return outbox


def record_of(outbox):
    return [(summary['told_ids'], np.asarray(summary['told_objectives']).tobytes(),
             summary['told_worlds']) for summary in outbox.summaries]


def test_a_raced_run_is_the_same_with_1_2_or_8_evaluators_in_any_order():
    task = raced_task()
    one = raced_run(task, ['a'])
    generator = np.random.default_rng(4)
    two = raced_run(task, ['a', 'b'], order=lambda count: range(count)[::-1])
    eight = raced_run(task, [f'e{index}' for index in range(8)],
                      order=lambda count: generator.permutation(count))
    assert record_of(one) == record_of(two) == record_of(eight)
    assert one.result['fitness'] == eight.result['fitness']
    worlds = [count for summary in one.summaries[:-1] for count in summary['told_worlds']]
    assert min(worlds) < 8 and max(worlds) == 8, 'the race stopped no candidate'


def test_a_raced_run_is_the_same_after_an_evaluator_dies_and_ignores_stale_rounds():
    task = raced_task()
    one = raced_run(task, ['a'])
    assert record_of(raced_run(task, ['a', 'b'], silent='b')) == record_of(one)
    assert record_of(raced_run(task, ['a', 'b'], stale=True)) == record_of(one)


def test_a_raced_run_resumes_from_its_summaries_to_the_same_end():
    task = raced_task()
    whole = raced_run(task, ['a'])
    recorded, genomes = {}, {}
    for summary in whole.summaries[:2]:
        for candidate_id, objectives in zip(summary['told_ids'], summary['told_objectives']):
            recorded[candidate_id] = objectives
    most = max(whole.summaries[0]['told_worlds'])
    worlds = {candidate_id: (count, most) for summary in whole.summaries[:2]
              for candidate_id, count in zip(summary['told_ids'], summary['told_worlds'])}
    recorded = with_worlds(recorded, worlds)   # as the bag reader gives them
    assert any(isinstance(value, RacedAnswer) for value in recorded.values())
    pending = whole.summaries[2]['told_ids'][0]
    recorded[pending] = np.array([0.0, 0.0])   # a round's answer of the batch in flight
    point = rebuild_search(task, 'old-run', 'the record', recorded, genomes)
    assert point.known == {} and point.evaluations_told == 2 * 12
    resumed = raced_run(task, ['a'], resumed=point)
    assert record_of(resumed)[:-1] == record_of(whole)[2:-1]
    assert resumed.result['fitness'] == whole.result['fitness']


@pytest.mark.parametrize('changes', [{'algorithm': 'mocma'}])
def test_racing_is_refused_where_its_bound_does_not_hold(changes):
    task = raced_task()
    with pytest.raises(ValueError, match='worlds.racing'):
        task.replace(**changes)
    with pytest.raises(ValueError, match='aggregate: worst'):
        task.replace(worlds=dataclasses.replace(task.worlds, aggregate='worst', fraction=0.5))
