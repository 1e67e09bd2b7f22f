"""Objectives: equations (2) to (6) on known values and hand-made traces."""

import math
import pathlib

from hand_codesign.core import load_task, parse_task
from hand_codesign.core.rotations import axis_angle_quaternion, quaternion_multiply, slerp
from hand_codesign.core.sim.objectives import (COLLISION_PENALTY, combine_worlds, goal_schedule,
                                               orientation_angle, position_distance,
                                               torque_penalty, weighted_fitness)
from hand_codesign.core.sim.worlds import object_state, WorldState
import numpy as np
import pytest
import yaml

TASKS = pathlib.Path(__file__).resolve().parents[3] / 'config' / 'tasks'
IDENTITY = (0.0, 0.0, 0.0, 1.0)
Z = (0.0, 0.0, 1.0)


def about(axis, angle):
    axis = np.array(axis, dtype=float) / np.linalg.norm(axis)
    return axis_angle_quaternion(axis, angle)


@pytest.mark.parametrize('first,second,angle', [
    (IDENTITY, IDENTITY, 0.0),
    (IDENTITY, (0.0, 0.0, 0.0, -1.0), 0.0),  # q and -q: the same rotation
    (IDENTITY, about(Z, math.pi / 2), math.pi / 2),
    (IDENTITY, about((1, 0, 0), math.pi), math.pi),
    (IDENTITY, about((1, 1, 1), math.pi / 3), math.pi / 3),
    (about(Z, math.radians(30)), about(Z, math.radians(100)), math.radians(70)),
    (about((0, 1, 0), 0.2), about((0, 1, 0), -0.3), 0.5),
    (about(Z, 3.0), about(Z, -3.0), 2 * math.pi - 6.0),  # the short way round
])
def test_orientation_angle_of_known_pairs(first, second, angle):
    assert orientation_angle(first, second) == pytest.approx(angle, abs=1e-7)
    assert orientation_angle(second, first) == pytest.approx(angle, abs=1e-7)


def test_orientation_angle_never_nan():
    nearly = np.array(about((1, 2, 3), 0.7)) * (1 + 1e-12)
    angle = orientation_angle(nearly, about((1, 2, 3), 0.7))
    assert np.isfinite(angle) and angle < 1e-5
    batch = orientation_angle(np.tile(IDENTITY, (3, 1)), [IDENTITY, about(Z, 1.0), IDENTITY])
    assert batch == pytest.approx([0.0, 1.0, 0.0])


def test_position_distances():
    assert position_distance((1.0, 2.0, 3.0), (4.0, 6.0, 3.0)) == pytest.approx(5.0)
    assert position_distance((1.0, 2.0, 3.0), (4.0, 6.0, 3.0), 'manhattan') == pytest.approx(7.0)
    assert position_distance((0.0, 0.0, 0.0), (-1.0, 1.0, -1.0), 'manhattan') == 3.0
    assert position_distance([(0, 0, 0), (0, 0, 2)], (0, 0, 0)) == pytest.approx([0.0, 2.0])


def test_torque_penalty_equation_2():
    assert torque_penalty([0.005, -0.012], threshold=0.008, weight=0.5) == pytest.approx(0.002)
    assert torque_penalty([0.005, -0.008], threshold=0.008, weight=0.5) == 0.0
    assert torque_penalty([], threshold=0.0, weight=0.5) == 0.0


def test_combining_worlds_equation_5():
    values = np.array([[0.1, 1.0], [0.3, 2.0]])
    assert combine_worlds(values, penalty=0.01) == pytest.approx([0.21, 1.51])
    assert list(combine_worlds(values, 0.01, collision=True)) == [COLLISION_PENALTY] * 2
    assert COLLISION_PENALTY == 10000.0
    assert weighted_fitness([0.2, 1.0], [1.0, 0.1]) == pytest.approx(0.3)


def test_the_worst_fraction_of_the_worlds_is_their_cvar():
    # 4 worlds x 2 objectives; each objective takes its own worst worlds
    values = np.array([[1.0, 10.0], [4.0, 20.0], [2.0, 40.0], [3.0, 30.0]])
    # a quarter of 4 worlds: the worst one; a half: the worst two
    assert list(combine_worlds(values, fraction=0.25)) == [4.0, 40.0]
    assert combine_worlds(values, 0.01, fraction=0.5) == pytest.approx([3.51, 35.01])
    # 1.5 worlds: the worst in full, the second worst with weight 0.5 (Rockafellar-Uryasev)
    assert combine_worlds(values, fraction=0.375) == pytest.approx([5.5 / 1.5, 55.0 / 1.5])
    # under one world: still the worst world; all of them: eq. (5), bit for bit
    assert list(combine_worlds(values, fraction=0.1)) == [4.0, 40.0]
    assert combine_worlds(values, 0.01, fraction=1.0).tobytes() == combine_worlds(
        values, 0.01).tobytes() == (0.01 + values.mean(axis=0)).tobytes()
    # the tail mean never falls as the tail shrinks
    tails = [combine_worlds(values, fraction=f) for f in (1.0, 0.8, 0.5, 0.3, 0.25)]
    assert all(np.all(a <= b) for a, b in zip(tails, tails[1:]))
    # 0.1 of 30 worlds is 3 worlds, whatever the rounding of 0.1 * 30
    many = np.arange(30.0).reshape(30, 1)
    assert list(combine_worlds(many, fraction=0.1)) == [28.0]
    assert list(combine_worlds(values, 0.01, collision=True, fraction=0.25)) == [
        COLLISION_PENALTY] * 2


def test_slerp():
    half = slerp(IDENTITY, about(Z, math.pi / 2), 0.5)
    assert orientation_angle(half, about(Z, math.pi / 4)) == pytest.approx(0.0, abs=1e-7)
    # from -90 to -180 degrees: continue clockwise, never back through 0
    path = [slerp(about(Z, -math.pi / 2), about(Z, -math.pi), f) for f in (0.25, 0.5, 0.75)]
    assert [orientation_angle(q, about(Z, -math.pi / 2)) for q in path] == pytest.approx(
        [math.pi / 8, math.pi / 4, 3 * math.pi / 8])


def small_task(position_goals, orientation_goals, early_termination=None, relative=False,
               symmetry=None):
    """Return Task 5 turned into a 1 s task with the given goals (every axis, every turn)."""
    document = yaml.safe_load((TASKS / 'task5.yaml').read_text())
    document['duration'] = 1.0
    document['policy']['duration'] = 1.0
    document['goals']['position'] = position_goals
    document['goals']['orientation'] = orientation_goals
    document['goals']['relative_to_start'] = relative
    document['goals'].pop('orientation_symmetry')
    if symmetry is not None:
        document['goals']['orientation_symmetry'] = symmetry
    if early_termination is not None:
        document['early_termination'] = early_termination
    return parse_task(yaml.safe_dump(document), source='small.yaml')


START = (0.0, 0.0, 0.02)


def test_trajectory_goals_are_interpolated():
    task = small_task(
        [{'time': 1.0, 'position': [0.1, 0.0, 0.02], 'trajectory': True}],
        [{'time': 1.0, 'orientation': {'axis': [0, 0, 1], 'angle': math.pi / 2},
          'trajectory': True}])
    schedule = goal_schedule(task)
    assert schedule.check_step_list == tuple(range(20, 201, 20))  # every 0.1 s
    assert list(schedule.objective_sizes) == [10, 10]
    samples = schedule.goal_samples()
    positions = {time: target for name, time, target in samples if name == 'position_1'}
    orientations = {time: target for name, time, target in samples if name == 'orientation_1'}
    assert positions[0.5] == pytest.approx([0.05, 0.0, 0.02])
    assert positions[0.1] == pytest.approx([0.01, 0.0, 0.02])
    assert positions[1.0] == pytest.approx([0.1, 0.0, 0.02])
    assert orientation_angle(orientations[0.5], IDENTITY) == pytest.approx(math.pi / 4)
    assert orientation_angle(orientations[0.2], IDENTITY) == pytest.approx(math.pi / 10)


def test_single_goals_and_second_goal_starts_from_the_first():
    task = small_task(
        [{'time': 0.3, 'position': [0.03, 0.0, 0.02], 'trajectory': False},
         {'time': 1.0, 'position': [0.1, 0.0, 0.02], 'trajectory': True}], [])
    schedule = goal_schedule(task)
    samples = [(time, target) for name, time, target in schedule.goal_samples()
               if name == 'position_2']
    assert [time for time, _ in samples] == pytest.approx([0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0])
    assert samples[0][1] == pytest.approx([0.04, 0.0, 0.02])
    assert list(schedule.objective_start_times) == pytest.approx([0.0, 0.3])
    assert not schedule.termination.any()  # no early termination in this task


def follow(schedule, trace, offset_from=None, offset=(0.0, 0.2, 0.0)):
    """Record the position goals' own targets, moved by `offset` from time `offset_from` on."""
    targets = {time: target for name, time, target in schedule.goal_samples()
               if name.startswith('position')}
    for time in schedule.check_times:
        position = np.array(targets.get(time, START))
        if offset_from is not None and time >= offset_from - 1e-9:
            position = position + offset
        if trace.record(position, IDENTITY):
            return True
    return False


def test_complete_trace_scores_the_mean_of_its_goals():
    task = small_task([{'time': 1.0, 'position': [0.1, 0.0, 0.02], 'trajectory': True}],
                      [{'time': 1.0, 'orientation': {'axis': [0, 0, 1], 'angle': 0.5},
                        'trajectory': False}])
    schedule = goal_schedule(task)
    trace = schedule.new_trace()
    assert not follow(schedule, trace, offset_from=0.9, offset=(0.0, 0.0, 0.03))
    # the last two of ten samples miss by 3 cm; the orientation misses by 0.5 rad
    assert trace.objective_values() == pytest.approx([0.006, 0.5])


def test_early_termination_charges_equation_6():
    task = small_task([{'time': 1.0, 'position': [0.1, 0.0, 0.02], 'trajectory': True}],
                      [{'time': 1.0, 'orientation': {'axis': [0, 0, 1], 'angle': 0.5},
                        'trajectory': False}],
                      early_termination={'distance': 0.05, 'angle': 0.3})
    schedule = goal_schedule(task)
    assert schedule.termination.all()
    trace = schedule.new_trace()
    assert follow(schedule, trace, offset_from=0.5)  # 20 cm off at t = 0.5 s: stop there
    assert trace.count == 5 and schedule.check_times[trace.count - 1] == pytest.approx(0.5)
    # position: 0.2 scored at 0.1..0.5 s, half of the window left: a = 0.5 of 10 samples
    # charged d_s each -> (0.5 * 10 * 0.05 + 0.2) / 10; orientation: single goal at 1 s,
    # a = 0.5 -> 0.5 * theta_s
    assert trace.objective_values() == pytest.approx([0.045, 0.15])


def test_early_termination_keeps_finished_objectives():
    task = small_task(
        [{'time': 0.3, 'position': [0.03, 0.0, 0.02], 'trajectory': False},
         {'time': 1.0, 'position': [0.1, 0.0, 0.02], 'trajectory': True}], [],
        early_termination={'distance': 0.05, 'angle': 0.3})
    schedule = goal_schedule(task)
    trace = schedule.new_trace()
    assert follow(schedule, trace, offset_from=0.5, offset=(0.0, 0.06, 0.0))
    remaining = (1.0 - 0.5) / (1.0 - 0.3)
    assert trace.objective_values() == pytest.approx(
        [0.0, (remaining * 7 * 0.05 + 0.06) / 7])


def test_stopping_before_a_window_costs_more_than_its_margin():
    task = small_task(
        [{'time': 0.3, 'position': [0.03, 0.0, 0.02], 'trajectory': True},
         {'time': 1.0, 'position': [0.1, 0.0, 0.02], 'trajectory': False}], [],
        early_termination={'distance': 0.05, 'angle': 0.3})
    schedule = goal_schedule(task)
    trace = schedule.new_trace()
    assert follow(schedule, trace, offset_from=0.1)  # off at the first check, t = 0.1 s
    assert trace.objective_values() == pytest.approx(
        [(2 / 3 * 3 * 0.05 + 0.2) / 3, 0.05 * (1.0 - 0.1) / (1.0 - 0.3)])


def test_cut_trace_needs_margins_without_early_termination():
    task = small_task([{'time': 1.0, 'position': [0.1, 0.0, 0.02], 'trajectory': False}], [])
    schedule = goal_schedule(task)
    with pytest.raises(ValueError, match='needs margins'):
        schedule.objective_values(np.zeros((1, 3)), np.zeros((1, 4)), 0)
    assert schedule.objective_values(np.zeros((1, 3)), np.zeros((1, 4)), 0,
                                     margins=[2.0]) == pytest.approx([2.0])


def test_goals_relative_to_the_start_move_with_each_world():
    task = small_task([{'time': 1.0, 'position': [0.1, 0.0, 0.02], 'trajectory': False}],
                      [{'time': 1.0, 'orientation': {'axis': [0, 0, 1], 'angle': 0.5},
                        'trajectory': False}], relative=True)
    schedule = goal_schedule(task)
    start = object_state(task, WorldState((0.003, -0.002, 0.0), 0.2, 0.0, 1.0, 1.0))
    trace = schedule.new_trace(start)
    turned = about(Z, 0.7)  # the goal's 0.5 rad plus the world's 0.2 rad
    assert not trace.record((0.103, -0.002, 0.02), turned)
    assert trace.objective_values() == pytest.approx([0.0, 0.0], abs=1e-9)
    assert schedule.pose_errors((0.103, -0.002, 0.02), turned, start) == pytest.approx(
        (0.0, 0.0), abs=1e-9)
    assert schedule.pose_errors(start.position, start.orientation, start) == pytest.approx(
        (0.1, 0.5))
    absolute = goal_schedule(load_task(TASKS / 'task5.yaml'))
    assert absolute.pose_errors((0.01, 0.0, 0.02), IDENTITY, start) == (0.0, 0.0)


def test_relative_goals_ask_for_the_same_world_turn_whatever_the_start_axis():
    """A start turned about x with a goal about z: the world's goal is R * q_start."""
    document = yaml.safe_load(small_task(
        [{'time': 1.0, 'position': [0.0, 0.0, 0.02], 'trajectory': False}],
        [{'time': 1.0, 'orientation': {'axis': [0, 0, 1], 'angle': 0.9}, 'trajectory': False}],
        relative=True).source_text)
    document['randomization']['orientation'] = {'axis': [1, 0, 0], 'range': [-1.5, 1.5]}
    task = parse_task(yaml.safe_dump(document), source='x_axis.yaml')
    schedule = goal_schedule(task)
    turn = about(Z, 0.9)  # the world-frame turn the goal asks for
    for delta in (-1.5, -0.4, 0.0, 0.7, 1.5):
        start = object_state(task, WorldState((0.01, 0.0, 0.0), delta, 0.0, 1.0, 1.0))
        perfect = quaternion_multiply(turn, start.orientation)
        position, orientation = schedule.world_goal(
            task.goals.position[-1].position, task.goals.orientation[-1].orientation, start)
        assert orientation_angle(orientation, perfect) == pytest.approx(0.0, abs=1e-7)
        assert list(position) == pytest.approx(list(start.position))  # goal = nominal start
        trace = schedule.new_trace(start)
        trace.record(position, perfect)
        assert trace.objective_values() == pytest.approx([0.0, 0.0], abs=1e-7)
        assert schedule.pose_errors(start.position, start.orientation, start) == \
            pytest.approx((0.0, 0.9))


def test_presets_build_schedules():
    task2 = goal_schedule(load_task(TASKS / 'task2.yaml'))  # 2 s, ten checks a second
    assert task2.num_checks == 20 and task2.termination.all()
    assert task2.num_steps == 400 and task2.check_step_list[-1] == 400
    task4 = goal_schedule(load_task(TASKS / 'task4.yaml'))
    assert task4.check_step_list == (200,) and list(task4.objective_sizes) == [1, 1]


def test_a_position_goal_measures_only_its_axes():
    assert position_distance((1.0, 2.0, 3.0), (4.0, 6.0, 10.0), mask=(1, 1, 0)) == 5.0
    assert position_distance((1.0, 2.0, 3.0), (4.0, 6.0, 10.0), 'manhattan',
                             mask=(1, 1, 0)) == 7.0
    assert position_distance((1.0, 2.0, 3.0), (4.0, 6.0, 10.0), mask=(0, 0, 1)) == 7.0
    task = small_task([{'time': 1.0, 'position': [0.1, 0.0, 0.02], 'axes': ['y', 'x'],
                        'trajectory': True}], [],
                      early_termination={'distance': 0.05, 'angle': 0.3})
    assert task.goals.position[0].axes == ('x', 'y')
    schedule = goal_schedule(task)
    trace = schedule.new_trace()
    assert not follow(schedule, trace, offset_from=0.1, offset=(0.0, 0.0, 0.2))  # height only
    assert trace.objective_values() == pytest.approx([0.0])
    assert schedule.pose_errors((0.1, 0.0, 0.5), IDENTITY) == pytest.approx((0.0, 0.0))
    trace = schedule.new_trace()
    assert follow(schedule, trace, offset_from=0.5, offset=(0.0, 0.2, 0.0))  # on the plane
    assert trace.count == 5
    assert schedule.pose_errors((0.1, 0.03, 0.02), IDENTITY)[0] == pytest.approx(0.03)


def test_symmetric_turns_are_the_objects_own_also_from_a_tilted_start():
    """A cube's 90-degree turn about its own z scores 0, a turn about the world's z does not."""
    document = yaml.safe_load(small_task(
        [], [{'time': 1.0, 'orientation': {'axis': [0, 0, 1], 'angle': 0.9},
              'trajectory': False}], relative=True,
        symmetry={'axis': [0, 0, 1], 'order': 4}).source_text)
    document['randomization']['orientation'] = {'axis': [1, 0, 0], 'range': [-0.5, 0.5]}
    task = parse_task(yaml.safe_dump(document), source='tilted.yaml')
    schedule = goal_schedule(task)
    start = object_state(task, WorldState((0.0, 0.0, 0.0), 0.5, 0.0, 1.0, 1.0))
    perfect = quaternion_multiply(about(Z, 0.9), start.orientation)
    for own_turn, error in ((math.pi / 2, 0.0), (-math.pi, 0.0), (0.3, 0.3),
                            (math.pi / 2 + 0.2, 0.2), (-math.pi / 2 - 0.7, 0.7)):
        measured = quaternion_multiply(perfect, about(Z, own_turn))
        trace = schedule.new_trace(start)
        for _ in schedule.check_times:
            trace.record((0.0, 0.0, 0.0), measured)
        assert trace.objective_values() == pytest.approx([error], abs=1e-7)
        assert schedule.pose_errors((0, 0, 0), measured, start)[1] == pytest.approx(
            error, abs=1e-7)
    world_turn = quaternion_multiply(about(Z, math.pi / 2), perfect)  # not a symmetry here
    assert schedule.pose_errors((0, 0, 0), world_turn, start)[1] > 0.1
