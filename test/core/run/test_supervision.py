"""
The supervision of a run's processes (core.run.supervision) driven by a fake clock, without ROS.

What a user relies on: an evaluator or recorder that dies is started again soon, under a new
evaluator id; one that keeps dying ends the run with a sentence naming it; a run whose
evaluators never join ends after the start deadline, and only then.
"""

from hand_codesign.core.run.supervision import node_name
from hand_codesign.core.run.supervision import RECORDER
from hand_codesign.core.run.supervision import Supervisor


class Clock:

    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now


def started_run(evaluators=2, **options):
    clock = Clock()
    supervisor = Supervisor(evaluators, clock=clock, **options)
    ids = [supervisor.started(role) for role in [RECORDER, 'evaluator-0', 'evaluator-1']
           [:evaluators + 1]]
    return supervisor, clock, ids


def test_first_processes_serve_under_their_role():
    _, _, ids = started_run()
    assert ids == ['recorder', 'evaluator-0', 'evaluator-1']


def test_dead_evaluator_restarts_soon_under_a_new_id():
    supervisor, clock, _ = started_run()
    supervisor.exited('evaluator-1', -9)
    assert supervisor.due() == []
    clock.now += 1.0
    assert supervisor.due() == ['evaluator-1']
    assert supervisor.started('evaluator-1') == 'evaluator-1-r1'
    assert supervisor.due() == [] and supervisor.gave_up is None
    clock.now += 120.0
    supervisor.exited('evaluator-1', 1)
    clock.now += 1.0
    assert supervisor.due() == ['evaluator-1']
    assert supervisor.started('evaluator-1') == 'evaluator-1-r2'
    assert supervisor.restarts == 2


def test_dead_recorder_restarts():
    supervisor, clock, _ = started_run()
    supervisor.exited(RECORDER, -9)
    clock.now += 1.0
    assert supervisor.due() == [RECORDER]


def test_restart_delay_doubles_for_a_role_that_keeps_dying():
    supervisor, clock, _ = started_run(max_restarts=5)
    for delay in (0.25, 0.5, 1.0, 2.0):
        supervisor.exited('evaluator-0', 1)
        start = clock.now
        clock.now = start + delay - 0.01
        assert supervisor.due() == []
        clock.now = start + delay + 0.01
        assert supervisor.due() == ['evaluator-0']
        supervisor.started('evaluator-0')


def test_a_role_dying_too_often_ends_the_run_and_says_which():
    supervisor, clock, _ = started_run(max_restarts=3, window=60.0)
    for _ in range(3):
        supervisor.exited('evaluator-1', 1)
        clock.now += 10.0
        assert supervisor.due() == ['evaluator-1']
        supervisor.started('evaluator-1')
    supervisor.exited('evaluator-1', 1)
    assert supervisor.due() == []
    assert 'evaluator evaluator-1 exited 4 times within 60 s' in supervisor.gave_up
    assert 'last exit code 1' in supervisor.gave_up


def test_exits_spread_beyond_the_window_never_end_the_run():
    supervisor, clock, _ = started_run(max_restarts=3, window=60.0)
    for restart in range(10):
        supervisor.exited('evaluator-0', -9)
        clock.now += 61.0
        assert supervisor.due() == ['evaluator-0']
        supervisor.started('evaluator-0')
    assert supervisor.gave_up is None


def test_start_deadline_ends_a_run_whose_evaluators_never_join():
    supervisor, clock, _ = started_run(start_timeout=30.0)
    clock.now += 29.0
    supervisor.due()
    assert supervisor.gave_up is None
    clock.now += 2.0
    supervisor.due()
    assert 'did not join within 30 s' in supervisor.gave_up


def test_no_start_deadline_once_the_optimizer_started_or_without_one():
    supervisor, clock, _ = started_run(start_timeout=30.0)
    supervisor.optimizer_ready()
    clock.now += 1000.0
    supervisor.due()
    assert supervisor.gave_up is None
    unlimited, clock, _ = started_run(start_timeout=0.0)
    clock.now += 10**6
    unlimited.due()
    assert unlimited.gave_up is None


def test_node_names_are_valid_and_distinct():
    names = [node_name(x) for x in ('evaluator-0', 'evaluator-1-r1', '7-host.local')]
    assert names == ['evaluator_0', 'evaluator_1_r1', 'evaluator_7_host_local']
