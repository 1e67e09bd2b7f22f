"""The dispatch rules: capacity, heartbeats, deadlines, duplicates and rejections."""

from dataclasses import dataclass

from hand_codesign.core.run.dispatch import Dispatcher
from hand_codesign.core.run.dispatch import DispatchError
import pytest


@dataclass
class Item:
    candidate_id: int


def make_dispatcher(count=6):
    dispatcher = Dispatcher(heartbeat_timeout=2.0, evaluation_timeout=10.0, max_attempts=3)
    dispatcher.add([Item(i) for i in range(count)])
    return dispatcher


def sent_ids(sent):
    return [(item.candidate_id, evaluator, attempt) for item, evaluator, attempt in sent]


def test_capacity_is_respected_and_load_balanced():
    dispatcher = make_dispatcher(10)
    dispatcher.heard_from('a', 2, now=0.0)
    dispatcher.heard_from('b', 2, now=0.0)
    sent = sent_ids(dispatcher.assignments(now=0.0))
    assert len(sent) == 4
    assert sorted(evaluator for _, evaluator, _ in sent) == ['a', 'a', 'b', 'b']
    assert dispatcher.assignments(now=0.1) == []
    assert dispatcher.complete(sent[0][0])
    assert sent_ids(dispatcher.assignments(now=0.2)) == [(4, sent[0][1], 0)]


def test_the_last_candidates_go_to_evaluators_with_nothing_queued():
    dispatcher = make_dispatcher(5)
    dispatcher.heard_from('a', 2, now=0.0)
    dispatcher.heard_from('b', 2, now=0.0)
    assert sent_ids(dispatcher.assignments(now=0.0)) == [(0, 'a', 0), (1, 'b', 0), (2, 'a', 0)]
    assert dispatcher.complete(0)
    assert dispatcher.assignments(now=0.1) == [], 'queued behind candidate 2 while b works'
    assert dispatcher.complete(1)
    assert sent_ids(dispatcher.assignments(now=0.2)) == [(3, 'b', 0)]
    assert dispatcher.complete(2) and dispatcher.complete(3)
    assert sent_ids(dispatcher.assignments(now=0.3)) == [(4, 'a', 0)]


def test_a_single_evaluator_always_has_the_next_candidate_queued():
    dispatcher = make_dispatcher(2)
    dispatcher.heard_from('a', 2, now=0.0)
    assert sent_ids(dispatcher.assignments(now=0.0)) == [(0, 'a', 0), (1, 'a', 0)]


def test_nothing_is_sent_before_an_evaluator_is_heard():
    dispatcher = make_dispatcher()
    assert dispatcher.assignments(now=0.0) == []


def test_silent_evaluator_loses_its_candidates():
    dispatcher = make_dispatcher(2)
    dispatcher.heard_from('a', 2, now=0.0)
    first = sent_ids(dispatcher.assignments(now=0.0))
    assert {evaluator for _, evaluator, _ in first} == {'a'}
    dispatcher.heard_from('b', 2, now=3.0)
    again = sent_ids(dispatcher.assignments(now=3.0))
    assert again == [(0, 'b', 1), (1, 'b', 1)]


def test_duplicates_and_unknown_ids_are_refused():
    dispatcher = make_dispatcher(1)
    dispatcher.heard_from('a', 1, now=0.0)
    dispatcher.assignments(now=0.0)
    assert dispatcher.complete(0)
    assert not dispatcher.complete(0)
    assert not dispatcher.complete(99)
    assert dispatcher.unfinished == 0


def test_overdue_candidate_goes_to_another_evaluator_first_answer_wins():
    dispatcher = make_dispatcher(1)
    dispatcher.heard_from('a', 1, now=0.0)
    dispatcher.heard_from('b', 1, now=0.0)
    assert len(dispatcher.assignments(now=0.0)) == 1
    dispatcher.heard_from('a', 1, now=11.0)
    dispatcher.heard_from('b', 1, now=11.0)
    resent = sent_ids(dispatcher.assignments(now=11.0))
    assert len(resent) == 1 and resent[0][2] == 1
    assert dispatcher.complete(0)
    assert not dispatcher.complete(0)


def test_rejected_candidate_moves_on_then_gives_up():
    dispatcher = make_dispatcher(1)
    for name in 'abcd':
        dispatcher.heard_from(name, 1, now=0.0)
    for _ in range(3):
        (item, evaluator, _), = dispatcher.assignments(now=0.0)
        assert dispatcher.reject(item.candidate_id, evaluator, 'bad genome')
    with pytest.raises(DispatchError, match='bad genome'):
        dispatcher.assignments(now=0.0)
