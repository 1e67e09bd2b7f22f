"""
A perfect motion scores zero: every preset, every world, starts turned about x, y and z.

"Perfect" is the object moved kinematically along its world's own goal trajectory: the
nominal goals interpolated as section III.C says (positions linearly, orientations by slerp,
from the nominal start at t = 0), carried into the world by GoalSchedule.world_goal. An object
that starts on the plane stays on it: its height is the resting height of its own scaled,
turned shape, so a goal that measured the height would charge it an error no hand can remove.
Errors within 1e-6: the arccos of eq. (4) is not more exact near 0.
"""

import dataclasses
import math
import pathlib

from hand_codesign.core import parse_task
from hand_codesign.core.evaluate import evaluate_design
from hand_codesign.core.rotations import quaternion_conjugate, quaternion_multiply, slerp
from hand_codesign.core.sim.objectives import combine_worlds, goal_schedule, orientation_angle
from hand_codesign.core.sim.pybullet_sim import Simulator
from hand_codesign.core.sim.worlds import object_state, world_states
from hand_codesign.core.task import resting_height
from hand_codesign.core.task.genome import genome_spec
import numpy as np
import pytest
import yaml

TASKS = pathlib.Path(__file__).resolve().parents[3] / 'config' / 'tasks'
PRESETS = sorted(TASKS.glob('*.yaml'))
AXES = {'x': [1, 0, 0], 'y': [0, 1, 0], 'z': [0, 0, 1]}
WORLDS = 8
TOLERANCE = 1e-6


def turned_about(path, axis):
    """Return the preset with its start turned about world `axis` (its range, else +-0.4)."""
    document = yaml.safe_load(path.read_text())
    orientation = document['randomization']['orientation']
    low, high = orientation['range']
    orientation['axis'] = AXES[axis]
    orientation['range'] = [low, high] if low != high else [-0.4, 0.4]
    document['world_states'] = WORLDS
    return parse_task(yaml.safe_dump(document), source=f'{path.name} about {axis}')


CASES = [(path, axis) for path in PRESETS for axis in AXES]
IDS = [f'{path.stem}-{axis}' for path, axis in CASES]


def nominal_pose(task, time):
    """Return the nominal goal trajectory's (position, orientation) at `time`."""
    spec = task.object_spec
    pose = []
    for kind, start, interpolate in (
            ('position', spec.position,
             lambda a, b, f: np.asarray(a) + f * (np.asarray(b) - np.asarray(a))),
            ('orientation', spec.orientation, slerp)):
        previous_time, value = 0.0, np.asarray(start, dtype=float)
        for goal in getattr(task.goals, kind):
            target = getattr(goal, kind)
            if time <= goal.time:
                fraction = (time - previous_time) / (goal.time - previous_time)
                value = interpolate(value, target, fraction)
                break
            previous_time, value = goal.time, np.asarray(target, dtype=float)
        pose.append(np.asarray(value, dtype=float))
    return tuple(pose)


def perfect_pose(task, schedule, state, time):
    """Return the world pose of the perfect motion at `time` in the world of `state`."""
    position, orientation = schedule.world_goal(*nominal_pose(task, time), state)
    position = np.array(position, dtype=float)
    if task.object_spec.start == 'plane':  # it lies on the plane, as its scale and turn rest it
        position[2] = resting_height(task.object_spec, state.scale, orientation)
    return position, np.asarray(orientation, dtype=float)


@pytest.mark.parametrize('path,axis', CASES, ids=IDS)
def test_the_perfect_motion_scores_zero_in_every_world(path, axis):
    task = turned_about(path, axis)
    schedule = goal_schedule(task)
    states = [object_state(task, world) for world in world_states(task)]
    assert len({state.orientation for state in states}) == WORLDS  # the starts do differ
    world_values, final_errors = [], []
    for state in states:
        trace = schedule.new_trace(state)
        for time in schedule.check_times:
            position, orientation = perfect_pose(task, schedule, state, time)
            assert not trace.record(position, orientation), f'stopped early at {time} s'
        assert trace.count == schedule.num_checks  # nothing stopped it early
        world_values.append(trace.objective_values())
        final_errors.append(schedule.pose_errors(position, orientation, state))
    objectives = combine_worlds(world_values)
    assert objectives.shape == (len(task.objective_names),)
    assert np.abs(objectives).max() < TOLERANCE, dict(zip(task.objective_names, objectives))
    assert np.abs(world_values).max() < TOLERANCE
    assert np.abs(final_errors).max() < TOLERANCE


RELATIVE = [(path, axis) for path, axis in CASES
            if yaml.safe_load(path.read_text())['goals'].get('relative_to_start')]


@pytest.mark.parametrize('path,axis', RELATIVE, ids=[f'{p.stem}-{a}' for p, a in RELATIVE])
def test_a_relative_goal_is_the_same_turn_and_shift_from_every_start(path, axis):
    task = turned_about(path, axis)
    schedule = goal_schedule(task)
    nominal = task.object_spec
    for name, time, target in schedule.goal_samples():
        for world in world_states(task):
            state = object_state(task, world)
            if name.startswith('orientation'):
                _, goal = schedule.world_goal(None, target, state)
                turn = quaternion_multiply(goal, quaternion_conjugate(state.orientation))
                wanted = quaternion_multiply(target, quaternion_conjugate(nominal.orientation))
                assert orientation_angle(turn, wanted) < TOLERANCE, (name, time)
            else:
                goal, _ = schedule.world_goal(target, None, state)
                assert np.subtract(goal, state.position) == pytest.approx(
                    np.subtract(target, nominal.position), abs=1e-12)


@pytest.mark.parametrize('path,axes', [(TASKS / 'task5.yaml', 'xy'),
                                       (TASKS / 'task5_along_x.yaml', 'x'),
                                       (TASKS.parent / 'reproduce' / 'task5.yaml', 'xy')],
                         ids=['task5', 'task5-along-x', 'pinned-task5'])
def test_the_plane_goals_ignore_the_resting_height_and_nothing_else(path, axes):
    """Task 5 scores a box at its goal zero at any scale; an offset on a scored axis counts."""
    task = turned_about(path, 'z')
    schedule = goal_schedule(task)
    assert schedule.objective_names == ('position_1', 'orientation_1')
    goal = np.array(task.goals.position[-1].position)
    offset = np.array([0.003, -0.004])
    scored = np.array([axis in axes for axis in 'xy'])
    for world in world_states(task):
        state = object_state(task, world)
        assert abs(state.position[2] - goal[2]) > 1e-4  # no box rests at the goal's height
        assert schedule.pose_errors((goal[0], goal[1], state.position[2]), (0, 0, 0, 1)) == \
            pytest.approx((0.0, 0.0), abs=1e-12)
        moved = (goal[0] + offset[0], goal[1] + offset[1], state.position[2])
        assert schedule.pose_errors(moved, (0, 0, 0, 1))[0] == pytest.approx(
            np.linalg.norm(offset[scored]))


def held_still(design, task):
    """Return the design with a controller that keeps every joint at its initial angle."""
    controller = design.controller
    if task.policy.kind == 'pd':
        initial = [joint.initial_angle for finger in design.hand.fingers
                   for joint in finger.joints]
        values = np.tile(initial, (len(controller.values), 1))
    else:
        values = np.zeros_like(controller.values)
    return dataclasses.replace(design, controller=dataclasses.replace(controller,
                                                                      values=values))


def drive_along_goals(task, design):
    """
    Evaluate `design` in real PyBullet with the object reset onto its perfect motion.

    At every step the rollout loop reports (on_frame) the object is put, at rest, onto the
    perfect pose of the next step; without gravity, and with no contact with the hand, it
    stays there through the step, so the loop reads back that pose from PyBullet, records it
    and scores it as in any evaluation.
    """
    # The hand is held still and gravity is switched off at the first frame: gravity
    # compensation, which reads the world's gravity when the rollout starts, would put it back.
    task = task.replace(policy=dataclasses.replace(task.policy, gravity_compensation=False))
    schedule = goal_schedule(task)
    states = [object_state(task, world) for world in world_states(task)]
    current = {}

    def on_world(index, simulator):
        current['state'] = states[index]

    def on_frame(step, simulator):
        client = simulator.client
        if step == 0:
            client.setGravity(0.0, 0.0, 0.0)
            # The hand takes no part in a perfect motion: a seed hand that holds its object
            # (Task 2's fingertips) would nudge it off its goals by a fraction of a millimetre.
            for link in range(-1, client.getNumJoints(simulator.hand)):
                client.setCollisionFilterPair(simulator.hand, simulator.object_body, link, -1,
                                              0)
        position, orientation = perfect_pose(task, schedule, current['state'],
                                             (step + 1) * task.time_step)
        client.resetBasePositionAndOrientation(simulator.object_body, position.tolist(),
                                               orientation.tolist())
        client.resetBaseVelocity(simulator.object_body, [0.0] * 3, [0.0] * 3)

    with Simulator() as simulator:
        return evaluate_design(design, task, simulator=simulator, on_frame=on_frame,
                               frame_every=1, on_world=on_world)


@pytest.mark.parametrize('axis', sorted(AXES))
@pytest.mark.parametrize('preset, turn', [('task2.yaml', math.pi),
                                          ('task2_there_and_back.yaml', 0.0)])
def test_a_sphere_driven_along_its_goals_in_pybullet_scores_zero(axis, preset, turn):
    """Task 2: a half turn (or, read as one motion, there and back), early termination armed."""
    task = turned_about(TASKS / preset, axis).replace(num_world_states=4)
    result = drive_along_goals(task, held_still(task.seed_design, task))
    assert not result.collision and result.unstable_worlds == 0
    assert result.simulated_time == pytest.approx(4 * task.duration)  # never stopped early
    assert np.abs(result.objectives).max() < TOLERANCE, result.objectives
    assert np.abs(result.final_errors).max() < TOLERANCE
    # the start, against the last goal: a half turn away, or where the motion ends
    assert result.initial_errors[:, 1] == pytest.approx([turn] * 4, abs=1e-9)


def test_a_box_driven_along_its_goals_in_pybullet_scores_zero():
    """Task 5: the box slides and turns to its goal on the plane, at every scale."""
    task = load_preset('task5.yaml').replace(num_world_states=4)
    spec = genome_spec(task)
    design = held_still(spec.decode(np.full(spec.size, 0.5)), task)
    result = drive_along_goals(task, design)
    assert not result.collision and result.unstable_worlds == 0
    assert result.objective_names == ('position_1', 'orientation_1')
    assert np.abs(result.objectives).max() < TOLERANCE, result.objectives
    assert np.abs(result.final_errors).max() < TOLERANCE
    assert (result.initial_errors > 1e-3).all()  # each world starts off its goals


def load_preset(name):
    return parse_task((TASKS / name).read_text(), source=name)


def test_a_turn_of_the_box_by_90_degrees_is_the_same_alignment():
    task = load_preset('task5.yaml')
    schedule = goal_schedule(task)
    goal = task.goals.position[-1].position
    for turn in (math.pi / 2, math.pi, -math.pi / 2, 2.0):
        about_z = (0.0, 0.0, math.sin(turn / 2), math.cos(turn / 2))
        expected = abs(math.remainder(turn, math.pi / 2))
        assert schedule.pose_errors(goal, about_z)[1] == pytest.approx(expected, abs=1e-7)
        trace = schedule.new_trace()
        for _ in schedule.check_times:
            trace.record(goal, about_z)
        assert trace.objective_values() == pytest.approx([0.0, expected], abs=1e-7)
    tilted = (math.sin(0.1), 0.0, 0.0, math.cos(0.1))  # 0.2 rad about x: no symmetry there
    assert schedule.pose_errors(goal, tilted)[1] == pytest.approx(0.2)
