"""Audits without ROS: a run with a lying evaluator ends as the run without it."""

from hand_codesign.core.outcomes import Answer
from hand_codesign.core.run.audits import Audits
from hand_codesign.core.run.audits import drawn
from hand_codesign.core.run.controller import RunController
import numpy as np
import pytest
from test_controller import Clock
from test_controller import objectives_of
from test_controller import Outbox
from test_controller import plain_loop
from test_controller import RUN
from test_controller import task5


def run_with(evaluators, lies, audit_fraction=0.1, population=6, own=()):
    """
    Run Task 5 to the end; lies(evaluator, candidate_id) says whether an answer is wrong.

    Every candidate sent is answered, the latest first, as in test_controller; a liar adds
    1e-3 to the true objectives. Return (result, summaries, outbox, told values).
    """
    task, clock = task5(population=population), Clock()
    outbox = Outbox()
    controller = RunController(task, RUN, outbox, clock=clock,
                               evaluators_expected=len(evaluators),
                               audit_fraction=audit_fraction, own_evaluators=own)
    for evaluator in evaluators:
        controller.heard_from(evaluator, 2)
    controller.tick()
    while outbox.result is None:
        sent = outbox.take()
        assert sent, 'the controller stopped sending before the run finished'
        for candidate, evaluator, _, _, _ in reversed(sent):
            clock.now += 0.5
            value = objectives_of(candidate.x, len(task.objective_names))
            if lies(evaluator, candidate.candidate_id):
                value = value + 1e-3
            controller.evaluated(RUN, candidate.candidate_id, evaluator, value, 0.5)
            for alive in evaluators:
                controller.heard_from(alive, 2)
    told = np.concatenate([np.asarray(s['told_objectives']).ravel()
                           for s in outbox.summaries if not s['final']])
    return outbox.result, outbox.summaries, outbox, told


def truth(population=6):
    best, _ = plain_loop(task5(population=population)).best
    return best


def test_an_evaluator_lying_on_every_answer_is_caught_before_any_is_told():
    result, summaries, outbox, _ = run_with(
        ('a', 'b', 'liar'), lambda evaluator, _: evaluator == 'liar')
    expected = truth()
    assert result['best_candidate_id'] == expected.candidate_id
    assert result['fitness'] == expected.fitness
    assert result['trust']['quarantined'] == ['liar']
    assert result['trust']['reevaluations'] >= 0 and result['evaluations'] == 18
    assert summaries[0]['quarantined'] == ['liar'], 'caught only after generation 0 was told'
    assert any('liar returned objectives that others contradict' in text
               for _, text in outbox.lines)
    after = [c for c, evaluator, _, _, _ in outbox.candidates if evaluator == 'liar']
    assert after == []


def test_without_audits_the_same_liar_changes_the_result():
    # shows that the test above can fail: the lies are told
    result, _, _, told = run_with(('a', 'b', 'liar'), lambda evaluator, _: evaluator == 'liar',
                                  audit_fraction=0.0)
    honest, _, _, honest_told = run_with(('a', 'b'), lambda *_: False, audit_fraction=0.0)
    assert not np.array_equal(told, honest_told)
    assert result['trust']['quarantined'] == [] and result['trust']['audit_evaluations'] == 0


def test_honest_evaluators_are_audited_and_the_told_values_do_not_change():
    _, _, _, alone = run_with(('a',), lambda *_: False)
    result, summaries, outbox, told = run_with(('a', 'b', 'c'), lambda *_: False)
    assert np.array_equal(told, alone), 'audits changed what the search was told'
    trust = result['trust']
    # one probation audit per evaluator, then only the drawn candidates
    lucky = sum(drawn(task5().seed, candidate_id, 0.1) for candidate_id in range(18))
    assert trust['quarantined'] == [] and 3 <= trust['audit_evaluations'] <= 3 + lucky
    assert result['evaluations'] == 18, 'audits counted as progress'
    audited = [i for s in summaries for i in s['audited_ids']]
    assert len(audited) == trust['audit_evaluations']
    assert {i for i in range(18) if drawn(task5().seed, i, 0.1)} <= set(audited)
    line = [text for _, text in outbox.lines if text.startswith('generation 3/3')][0]
    assert '18 evaluations' in line and f'{trust["audit_evaluations"]} audit evaluations' in line


def test_a_single_evaluator_is_not_audited():
    result, _, _, _ = run_with(('a',), lambda *_: False)
    assert result['trust']['audit_evaluations'] == 0 and result['evaluations'] == 18


def test_after_its_probation_a_lie_is_caught_only_when_its_candidate_is_drawn():
    seed, fraction = task5().seed, 0.3
    later = 12   # the liar answers generations 0 and 1 honestly and passes its probation

    def drawn_lies(evaluator, candidate_id):
        return (evaluator == 'liar' and candidate_id >= later
                and drawn(seed, candidate_id, fraction))

    def undrawn_lies(evaluator, candidate_id):
        return (evaluator == 'liar' and candidate_id >= later
                and not drawn(seed, candidate_id, fraction))

    caught, _, _, _ = run_with(('a', 'b', 'liar'), drawn_lies, fraction, population=10)
    assert caught['trust']['quarantined'] == ['liar']
    assert caught['fitness'] == truth(population=10).fitness
    missed, _, _, told = run_with(('a', 'b', 'liar'), undrawn_lies, fraction, population=10)
    _, _, _, honest = run_with(('a', 'b'), lambda *_: False, fraction, population=10)
    assert missed['trust']['quarantined'] == [] and not np.array_equal(told, honest)


def test_the_runs_own_evaluators_are_audited_on_probation_only():
    own = ('evaluator-0', 'evaluator-1')
    result, _, _, told = run_with(('evaluator-0', 'evaluator-1-r2'), lambda *_: False, 0.5,
                                  population=10, own=own)
    assert result['trust']['audit_evaluations'] == 2   # one probation each, nothing drawn
    _, _, _, honest = run_with(('a', 'b'), lambda *_: False, 0.5, population=10)
    assert np.array_equal(told, honest)


def test_an_evaluator_on_another_host_is_still_drawn_beside_the_runs_own():
    seed, fraction, later = task5().seed, 0.3, 12

    def drawn_lies(evaluator, candidate_id):
        return (evaluator == 'host-b' and candidate_id >= later
                and drawn(seed, candidate_id, fraction))

    caught, _, _, _ = run_with(('evaluator-0', 'evaluator-1', 'host-b'), drawn_lies, fraction,
                               population=10, own=('evaluator-0', 'evaluator-1'))
    assert caught['trust']['quarantined'] == ['host-b']
    assert caught['fitness'] == truth(population=10).fitness


def test_the_draws_come_from_the_seed_and_have_the_fraction():
    first = [drawn(7, i, 0.1) for i in range(2000)]
    assert first == [drawn(7, i, 0.1) for i in range(2000)]
    assert first != [drawn(8, i, 0.1) for i in range(2000)]
    assert 0.08 < np.mean(first) < 0.12
    assert not any(drawn(7, i, 0.0) for i in range(100))


def test_forged_answers_of_this_run_are_counted_in_the_summaries():
    task, clock = task5(), Clock()
    controller = RunController(task, RUN, Outbox(), clock=clock)
    controller.forged(RUN, 'evaluator-0')
    controller.forged('another-run', 'evaluator-0')
    assert controller.trust_counts()['rejected_evaluations'] == 1


def test_a_mismatch_is_settled_by_a_third_and_the_liar_quarantined():
    audits = Audits(seed=7, fraction=0.0001)
    audits.start_batch()
    assert audits.take(1, 'a', [1.0], True).value is None      # a is on probation
    verdict = audits.take(1, 'b', [1.0], True)
    assert verdict.value.tolist() == [1.0] and audits.passed == {'a', 'b'}
    settled = audits.take(2, 'a', [2.0], True)                  # passed: taken as is
    assert settled.value.tolist() == [2.0]
    assert audits.take(3, 'c', [3.5], True).exclude == {'c'}
    disagree = audits.take(3, 'a', [3.0], True)
    assert disagree.value is None and disagree.exclude == {'a', 'c'}
    verdict = audits.take(3, 'b', [3.0], True)
    assert verdict.value.tolist() == [3.0] and verdict.liars == ['c']
    assert audits.quarantined == ['c'] and audits.audit_evaluations == 3


def test_a_quarantine_redoes_what_only_the_liar_answered():
    audits = Audits(seed=7, fraction=0.0001)
    audits.start_batch()
    audits.passed.update({'a', 'liar'})        # a liar that passed its probation
    assert audits.take(1, 'liar', [9.0], True).value.tolist() == [9.0]
    audits.take(2, 'b', [2.0], True)            # b on probation: audited ...
    verdict = audits.take(2, 'liar', [2.5], True)  # ... by the liar, who disagrees
    assert verdict.exclude == {'b', 'liar'}
    verdict = audits.take(2, 'a', [2.0], True)
    assert verdict.liars == ['liar'] and verdict.redo == [1]
    assert audits.reevaluations == 1


@pytest.mark.parametrize('evaluators', [('a', 'b', 'c', 'liar'), ('liar', 'a', 'b', 'c', 'd')])
def test_the_result_is_the_same_with_any_number_of_honest_evaluators(evaluators):
    result, _, _, _ = run_with(evaluators, lambda evaluator, _: evaluator == 'liar')
    assert result['fitness'] == truth().fitness and result['trust']['quarantined'] == ['liar']


def test_answers_of_an_evaluator_on_probation_wait_for_its_first_audit():
    audits = Audits(seed=7, fraction=0.0001)
    audits.start_batch()
    assert audits.take(1, 'a', [1.0], True).exclude == {'a'}   # a's probation audit
    held = audits.take(2, 'a', [2.0], True)
    assert held.value is None and not held.exclude and audits.holding
    verdict = audits.take(1, 'b', [1.0], True)
    assert verdict.value.tolist() == [1.0] and {2: [2.0]} == {
        key: value.tolist() for key, value in verdict.released.items()}
    assert not audits.holding and audits.audit_evaluations == 1
    audits.take(3, 'liar', [3.5], True)
    audits.take(4, 'liar', [4.5], True)                         # held
    audits.take(3, 'a', [3.0], True)
    verdict = audits.take(3, 'b', [3.0], True)
    assert verdict.liars == ['liar'] and verdict.redo == [4] and not audits.holding


def test_an_audit_no_other_live_evaluator_can_do_is_taken_unaudited():
    """Evaluator b falls silent after the start: a's answers cannot be audited, yet all end."""
    task, clock, outbox = task5(population=6), Clock(), Outbox()
    controller = RunController(task, RUN, outbox, clock=clock, evaluators_expected=2,
                               audit_fraction=0.1)
    for evaluator in ('a', 'b'):
        controller.heard_from(evaluator, 2)
    controller.tick()
    size = len(task.objective_names)
    while outbox.result is None:
        assert clock.now < 3600.0, 'the run waits without end for an auditor'
        for candidate, evaluator, _, _, _ in outbox.take():
            if evaluator == 'a':
                controller.evaluated(RUN, candidate.candidate_id, 'a',
                                     objectives_of(candidate.x, size), 0.5)
        clock.now += 1.0
        controller.heard_from('a', 2)
        controller.tick()
    expected = plain_loop(task).best[0]
    assert outbox.result['best_candidate_id'] == expected.candidate_id
    assert any('no other evaluator alive to audit' in text for _, text in outbox.lines)


def test_an_auditor_that_differs_only_in_outcomes_disagrees_and_the_first_answer_is_taken():
    audits = Audits(seed=1, fraction=0.1)
    honest = Answer.of([0.1, 0.2], ('limit_rest',), [0.5])
    first = audits.take(7, 'a', honest, True)  # a's first answer: audited on probation
    assert first.value is None and first.exclude == {'a'}
    second = audits.take(7, 'liar', Answer.of([0.1, 0.2], ('limit_rest',), [1.0]), True)
    assert second.value is None and second.exclude == {'a', 'liar'}
    third = audits.take(7, 'b', Answer.of([0.1, 0.2], ('limit_rest',), [0.5]), True)
    assert third.value is honest and third.liars == ['liar']
