"""The simulator: start collisions, deterministic rollouts, instability, frames."""

import dataclasses
import pathlib

from hand_codesign.core import genome_spec, load_task, Simulator, world_states
from hand_codesign.core.design import ControllerDesign, FingerDesign, JointDesign
from hand_codesign.core.evaluate import evaluate_design, UNSTABLE_PENALTY
from hand_codesign.core.sim.events import EventPlan
from hand_codesign.core.sim.hand import hand_model
from hand_codesign.core.sim.objectives import COLLISION_PENALTY, goal_schedule
from hand_codesign.core.sim.policies import make_policy
from hand_codesign.core.sim.pybullet_sim import object_shape
from hand_codesign.core.sim.worlds import object_state, ObjectState
import numpy as np
import pytest

TASKS = pathlib.Path(__file__).resolve().parents[3] / 'config' / 'tasks'


@pytest.fixture(scope='module')
def task():
    return load_task(TASKS / 'task5.yaml').replace(num_world_states=4)


@pytest.fixture(scope='module')
def design(task):
    """Return a Task 5 design that moves the box: fingers bent away, then pushing it."""
    # A positive angle turns a finger towards -x (the joint axes are along world +y).
    fingers = tuple(FingerDesign(
        position=(x, 0.0), segment_lengths=(0.06, 0.06),
        joints=(JointDesign(axis_angle=np.pi / 2, initial_angle=angle, lower_limit=-1.2,
                            upper_limit=1.2),) * 2) for x, angle in ((-0.055, 0.2), (0.055, -0.2)))
    base = genome_spec(task).decode(genome_spec(task).initial_mean())
    torques = np.array([[-0.006, -0.004, 0.008, 0.003], [-0.01, -0.002, 0.004, 0.002]])
    return dataclasses.replace(base, hand=dataclasses.replace(base.hand, fingers=fingers),
                               controller=ControllerDesign(kind='torque', values=torques))


def with_fingers(design, positions=None, lengths=None, angle=None):
    """Return the design with other finger positions, segment lengths or initial angles."""
    fingers = []
    for index, finger in enumerate(design.hand.fingers):
        joints = finger.joints if angle is None else tuple(
            dataclasses.replace(joint, initial_angle=angle) for joint in finger.joints)
        fingers.append(dataclasses.replace(
            finger, joints=joints,
            position=finger.position if positions is None else positions[index],
            segment_lengths=finger.segment_lengths if lengths is None else lengths))
    return dataclasses.replace(design, hand=dataclasses.replace(design.hand,
                                                                fingers=tuple(fingers)))


def built(simulator, task, design):
    """Build the design on the simulator; return its world objects and the policy."""
    model = hand_model(design.hand, task.hand)
    simulator.build(task, model)
    states = [object_state(task, world) for world in world_states(task)]
    objects = [(state, object_shape(simulator.client, state, 'box')) for state in states]
    policy = make_policy(task.policy, design.controller, model.initial_angles, task.time_step)
    return objects, policy


def test_a_design_starting_in_the_ground_collides(task, design):
    straight = with_fingers(design, lengths=(0.09, 0.09), angle=0.0)  # reaches below z = 0
    result = evaluate_design(straight, task)
    assert result.collision
    np.testing.assert_array_equal(result.objectives, [COLLISION_PENALTY] * 2)
    assert (result.world_objectives == COLLISION_PENALTY).all()
    assert result.fitness == COLLISION_PENALTY * sum(task.objective_weights)  # 1.0 + 0.1
    assert result.simulated_time == 0.0
    np.testing.assert_array_equal(result.final_errors, result.initial_errors)
    assert not evaluate_design(design, task).collision


def test_start_contacts_with_the_object_and_between_fingers(task, design):
    with Simulator() as simulator:
        objects, _ = built(simulator, task, design)
        assert not simulator.start_collisions(objects)
        # a box put where the first segment of finger 0 is
        segment = simulator.client.getLinkState(simulator.hand, 0)[0]
        state = dataclasses.replace(objects[0][0], position=tuple(segment))
        assert simulator.start_collisions([(state, objects[0][1])])
        # a box beside it (half size 2 cm; the tilted capsule reaches 1.3 cm) is no contact
        beside = (segment[0] + 0.04, segment[1], segment[2])
        state = ObjectState(position=beside, orientation=(0.0, 0.0, 0.0, 1.0), scale=1.0,
                            mass=0.03, friction=0.3, size=(0.04, 0.04, 0.04))
        shape = object_shape(simulator.client, state, 'box')
        assert not simulator.start_collisions([(state, shape)])
        # two fingers on the same spot of the palm overlap: a collision of the hand with itself
        crossed = with_fingers(design, positions=((0.0, 0.0), (0.0, 0.0)))
        objects, _ = built(simulator, task, crossed)
        assert simulator.start_collisions(objects)


def traces(simulator, task, design, order):
    """Return {world: (recorded positions, final pose)} of the worlds run in `order`."""
    objects, policy = built(simulator, task, design)
    schedule = goal_schedule(task)
    result = {}
    for index in order:
        rollout = simulator.rollout(*objects[index], policy, schedule)
        result[index] = (rollout.trace.positions.tobytes(), rollout.final_position,
                         rollout.final_orientation, rollout.steps)
    return result


def test_rollouts_are_bit_identical_to_fresh_worlds_in_any_order(task, design):
    with Simulator() as simulator:
        fresh = {index: traces(simulator, task, design, [index])[index] for index in range(4)}
        assert traces(simulator, task, design, [0, 1, 2, 3]) == fresh
        assert traces(simulator, task, design, [3, 1, 0, 2]) == fresh
        assert traces(simulator, task, design, [2, 2, 2]) == {2: fresh[2]}
    start = object_state(task, world_states(task)[0]).position
    assert np.linalg.norm(np.subtract(fresh[0][1], start)) > 1e-3  # the box did move


def test_rollouts_after_the_hand_pressed_the_ground_are_bit_identical_too(task, design):
    # fingers reaching 3 mm above the ground, pushed down onto it
    fingers = tuple(FingerDesign(
        position=(x, 0.0), segment_lengths=(0.0737, 0.0737),
        joints=(JointDesign(np.pi / 2, sign * 0.267, -1.5, 1.5),
                JointDesign(np.pi / 2, -sign * 0.534, -1.5, 1.5)))
        for x, sign in ((-0.055, 1.0), (0.055, -1.0)))
    torques = np.array([[-0.0002, 0.0031, -0.0048, -0.0039], [0.0003, -0.0086, 0.0018, -0.0064]])
    pressing = dataclasses.replace(design, hand=dataclasses.replace(design.hand, fingers=fingers),
                                   controller=ControllerDesign(kind='torque', values=torques))
    touching = []

    def on_frame(step, simulator):
        if step == 300:
            touching.append(len(simulator.client.getContactPoints(simulator.hand,
                                                                  simulator.ground)))

    with Simulator() as simulator:
        objects, policy = built(simulator, task, pressing)
        assert not simulator.start_collisions(objects)
        for world in objects:
            simulator.rollout(*world, policy, goal_schedule(task), on_frame, 300)
        assert all(touching)
        fresh = {index: traces(simulator, task, pressing, [index])[index] for index in range(4)}
        assert traces(simulator, task, pressing, [1, 3, 2, 0]) == fresh


def test_joints_stop_at_their_limits(task, design):
    limited = dataclasses.replace(design, controller=ControllerDesign(
        kind='torque', values=np.array([[0.05, -0.05, -0.05, 0.05]] * 2)))
    angles = []

    def on_frame(step, simulator):
        angles.append([state[0] for state in simulator.client.getJointStates(
            simulator.hand, [0, 1, 2, 3])])

    evaluate_design(limited, task, worlds=world_states(task)[:1], on_frame=on_frame,
                    frame_every=10)
    first_joints = np.abs(angles)[:, [0, 2]]  # pushed outwards, against their limit 1.2
    np.testing.assert_allclose(first_joints[-5:], 1.2, atol=1e-3)
    # a step at Bullet's 100 rad/s cap is 0.5 rad; the limit takes back any overshoot
    assert first_joints.max() < 1.2 + 0.1


def test_an_unstable_simulation_ends_with_a_finite_penalty_and_a_flag(task, design):
    before = evaluate_design(design, task)
    broken = dataclasses.replace(design, controller=ControllerDesign(
        kind='torque', values=np.full((2, 4), np.nan)))
    result = evaluate_design(broken, task)
    assert result.unstable_worlds == 4 and not result.collision
    assert (result.world_objectives == UNSTABLE_PENALTY).all()
    assert np.isfinite(result.objectives).all() and np.isfinite(result.fitness)
    assert np.isfinite(result.final_errors).all()
    assert result.simulated_time == pytest.approx(4 * 1.0)  # stopped at the 1 s joint watch
    assert _same(evaluate_design(design, task), before)  # the simulator is as good as new


def _same(first, second):
    return all(np.array_equal(getattr(first, name), getattr(second, name))
               for name in ('objectives', 'world_objectives', 'final_errors'))


def test_frames_come_at_their_steps_and_change_nothing(task, design):
    frames = []

    def on_frame(step, simulator):
        frames.append((step, simulator.client.getBasePositionAndOrientation(
            simulator.object_body)[0]))

    plain = evaluate_design(design, task)
    framed = evaluate_design(design, task, on_frame=on_frame, frame_every=50)
    assert _same(plain, framed)
    assert [step for step, _ in frames] == [0, 50, 100, 150, 200, 250, 300] * 4
    assert frames[0][1] == pytest.approx(object_state(task, world_states(task)[0]).position)


def test_event_plan_merges_checks_watches_and_frames(task):
    schedule = goal_schedule(task)  # one goal at 1.5 s: step 300
    plan = EventPlan(schedule, task.time_step)
    assert plan.num_steps == 300
    assert plan.steps == (100, 200, 300, -1)  # watches twice a second; the check at 300
    assert plan.kinds[-2] & 1 and plan.kinds[-2] & 2  # step 300: a check and a watch
    assert [bool(kind & 4) for kind in plan.kinds[:-1]].count(True) == 1  # joints at 1 s
    framed = EventPlan(schedule, task.time_step, frame_every=30)
    assert framed.steps == (30, 60, 90, 100, 120, 150, 180, 200, 210, 240, 270, 300, -1)


def test_a_rendering_simulator_shows_hand_and_object_in_its_frames(task, design):
    seen = []

    def on_frame(step, simulator):
        client = simulator.client
        view = client.computeViewMatrix((0.3, -0.3, 0.25), (0.0, 0.0, 0.07), (0.0, 0.0, 1.0))
        projection = client.computeProjectionMatrixFOV(45.0, 1.0, 0.01, 5.0)
        segmentation = client.getCameraImage(64, 64, view, projection)[4]
        bodies = {-1, simulator.ground, simulator.hand, simulator.object_body}  # -1: sky
        seen.append(set(np.unique(segmentation)) == bodies)

    with Simulator(rendering=True) as simulator:
        rendered = evaluate_design(design, task, simulator=simulator, on_frame=on_frame,
                                   frame_every=150, worlds=world_states(task)[:1])
    assert seen == [True] * 3
    assert _same(rendered, evaluate_design(design, task, worlds=world_states(task)[:1]))
