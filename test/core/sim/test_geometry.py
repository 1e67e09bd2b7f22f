"""core.sim.geometry: what a viewer draws is where the simulated hand, object and goals are."""

import math
import pathlib

from hand_codesign.core.sim.geometry import design_shapes
from hand_codesign.core.sim.geometry import goal_poses
from hand_codesign.core.sim.geometry import hand_shapes
from hand_codesign.core.sim.geometry import link_frames
from hand_codesign.core.sim.geometry import rotate
from hand_codesign.core.sim.hand import hand_model
from hand_codesign.core.sim.pybullet_sim import Simulator
from hand_codesign.core.sim.worlds import object_state
from hand_codesign.core.sim.worlds import WorldState
from hand_codesign.core.task import load_task
from hand_codesign.core.task.genome import genome_spec
import numpy as np
import pytest

TASKS = pathlib.Path(__file__).resolve().parents[3] / 'config' / 'tasks'


def random_design(task, seed):
    spec = genome_spec(task)
    return spec.decode(np.random.default_rng(seed).random(len(spec.names)))


def palm_pose(task):
    return tuple(task.hand.base_position), tuple(task.hand.base_orientation)


def same_rotation(first, second):
    return abs(abs(float(np.dot(first, second))) - 1.0) < 1e-6


@pytest.mark.parametrize('name, seed', [('task5.yaml', 1), ('task1.yaml', 2), ('task4.yaml', 3)])
def test_link_frames_are_pybullets_at_any_joint_angles(name, seed):
    task = load_task(TASKS / name)
    model = hand_model(random_design(task, seed).hand, task.hand)
    angles = np.random.default_rng(seed).uniform(-1.0, 1.0, model.num_joints)
    with Simulator() as simulator:
        simulator.build(task, model)
        client = simulator.client
        indices = list(range(model.num_joints))
        for wanted in (None, angles):
            if wanted is not None:
                for index, angle in zip(indices, wanted):
                    client.resetJointState(simulator.hand, index, float(angle))
            states = client.getLinkStates(simulator.hand, indices,
                                          computeForwardKinematics=True)
            frames = link_frames(model, palm_pose(task), wanted)
            for (position, orientation), state in zip(frames, states):
                assert np.allclose(position, state[4], atol=1e-6)
                assert same_rotation(orientation, state[5])


def test_a_design_is_drawn_as_palm_capsules_axes_object_and_goals():
    task = load_task(TASKS / 'task5.yaml')
    design = random_design(task, 4)
    model = hand_model(design.hand, task.hand)
    shapes = design_shapes(task, design)
    groups = {}
    for shape in shapes:
        groups.setdefault(shape.group, []).append(shape)
    assert [shape.kind for shape in groups['palm']] == ['box']
    assert groups['palm'][0].size == tuple(task.hand.palm_size)
    cylinders = [shape for shape in groups['segments'] if shape.kind == 'cylinder']
    spheres = [shape for shape in groups['segments'] if shape.kind == 'sphere']
    assert len(cylinders) == model.num_joints and len(spheres) == 2 * model.num_joints
    assert len(groups['joint_axes']) == model.num_joints
    assert [shape.kind for shape in groups['object']] == [task.object_spec.shape]
    assert len(groups['goals']) == len(goal_poses(task, object_state(task,
                                                                     WorldState.nominal())))
    # each capsule: its two spheres lie on the segment, a cylinder height apart, and the
    # cylinder's centre between them
    frames = link_frames(model, palm_pose(task))
    for index, (link, frame) in enumerate(zip(model.links, frames)):
        first, last = spheres[2 * index], spheres[2 * index + 1]
        assert math.isclose(np.linalg.norm(np.subtract(last.position, first.position)),
                            link.cylinder_height, abs_tol=1e-12)
        assert np.allclose(cylinders[index].position,
                           np.add(first.position, last.position) / 2, atol=1e-12)
        assert cylinders[index].size == (2 * link.radius, 2 * link.radius,
                                         link.cylinder_height)
        # the cylinder's own z axis runs along the segment
        along = rotate(cylinders[index].orientation, (0.0, 0.0, 1.0))
        assert np.allclose(np.cross(along, np.subtract(last.position, first.position)), 0.0,
                           atol=1e-12)


def test_joint_axes_point_along_the_joints_axes_in_the_world():
    task = load_task(TASKS / 'task5.yaml')
    model = hand_model(random_design(task, 5).hand, task.hand)
    angles = np.linspace(-0.8, 0.8, model.num_joints)
    with Simulator() as simulator:
        simulator.build(task, model)
        client = simulator.client
        for index, angle in enumerate(angles):
            client.resetJointState(simulator.hand, index, float(angle))
        frames = link_frames(model, palm_pose(task), angles)
        arrows = [shape for shape in hand_shapes(model, palm_pose(task), frames)
                  if shape.kind == 'arrow']
        for index, arrow in enumerate(arrows):
            info = client.getJointInfo(simulator.hand, index)
            state = client.getLinkState(simulator.hand, index, computeForwardKinematics=True)
            start, end = np.array(arrow.points)
            assert np.allclose(start, state[4], atol=1e-6)        # at the joint
            axis = rotate(state[5], info[13])                     # PyBullet's joint axis
            direction = (end - start) / np.linalg.norm(end - start)
            assert np.allclose(direction, axis, atol=1e-6)


def test_goals_are_drawn_in_the_world_of_the_start():
    task = load_task(TASKS / 'task5.yaml')
    state = object_state(task, WorldState((0.01, -0.02, 0.0), 0.0, 0.0, 1.0, 1.0))
    poses = goal_poses(task, state)
    assert [time for time, _, _ in poses] == sorted(
        {goal.time for goal in task.goals.position + task.goals.orientation})
    last = task.goals.position[-1]
    expected = np.array(last.position)
    if task.goals.relative_to_start:
        expected = expected + np.subtract(state.position, task.object_spec.position)
    time, position, _ = next(pose for pose in poses if pose[0] == last.time)
    assert np.allclose(position, expected)
