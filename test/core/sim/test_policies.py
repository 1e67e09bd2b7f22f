"""Policies: torque schedules, gravity compensation and the feed-forward PD law of eq. (1)."""

import dataclasses
import math

from hand_codesign.core.design import ControllerDesign, FingerDesign, HandDesign, JointDesign
from hand_codesign.core.sim.hand import build_hand, hand_model
from hand_codesign.core.sim.policies import make_policy, PDPolicy, TorquePolicy
from hand_codesign.core.task import HandSpec, PolicySpec
import numpy as np
import pybullet
from pybullet_utils.bullet_client import BulletClient
import pytest

TIME_STEP = 0.005
# Identity base: the finger sticks out horizontally along world +y and its joints (axis angle
# 0: the x axis) swing it up and down, so gravity pulls on every joint.
HAND = HandSpec(base_position=(0.0, 0.0, 0.5), base_orientation=(0.0, 0.0, 0.0, 1.0),
                palm_size=(0.06, 0.01, 0.06), segment_radius=0.007, segment_density=1000.0)


# Base orientations of the presets: palm up (Tasks 1 to 3: the fingers point up) and palm down
# (Tasks 4 to 6: they hang), and one turned about every axis.
PALM_UP = (math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5))
PALM_DOWN = (-math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5))
TILTED = tuple(pybullet.getQuaternionFromEuler((0.4, -0.7, 1.1)))


def build_finger(client, hand=HAND, lengths=(0.06, 0.05), base_orientation=None):
    """Build a free two-joint finger without ground; return (body, model)."""
    joints = (JointDesign(axis_angle=0.0, initial_angle=0.2),
              JointDesign(axis_angle=0.0, initial_angle=-0.1))
    design = HandDesign(fingers=(FingerDesign(position=(0.0, 0.0), segment_lengths=lengths,
                                              joints=joints),), friction=0.5)
    model = hand_model(design, hand)
    orientation = hand.base_orientation if base_orientation is None else base_orientation
    return build_hand(client, model, hand.base_position, orientation), model


@pytest.fixture
def client():
    """Return a DIRECT client with gravity and the task's time step."""
    client = BulletClient(connection_mode=pybullet.DIRECT)
    client.setGravity(0.0, 0.0, -9.81)
    client.setPhysicsEngineParameter(fixedTimeStep=TIME_STEP)
    yield client
    client.disconnect()


@pytest.fixture
def finger(client):
    """Return (client, body, model) of a free two-joint finger without ground."""
    body, model = build_finger(client)
    return client, body, model


def run(client, body, policy, steps):
    """Drive the body with the policy for `steps` steps; return the joint angles."""
    torques = policy.start(client, body, steps)
    joints = list(range(policy.num_joints))
    for step in range(steps):
        client.setJointMotorControlArray(body, joints, client.TORQUE_CONTROL,
                                         forces=torques(step))
        client.stepSimulation()
    return np.array([state[0] for state in client.getJointStates(body, joints)])


def test_constant_torques_hold_each_interval_then_stop():
    policy = TorquePolicy([[1.0, 2.0], [3.0, -4.0]], duration=1.0, mode='constant',
                          time_step=TIME_STEP)
    np.testing.assert_array_equal(policy.torque_at([0.0, 0.495, 0.5, 0.995, 1.0, 1.3]),
                                  [[1, 2], [1, 2], [3, -4], [3, -4], [0, 0], [0, 0]])
    rows = policy.schedule(300)
    assert len(rows) == 300
    assert rows[0] == [1.0, 2.0] and rows[99] == [1.0, 2.0] and rows[100] == [3.0, -4.0]
    assert rows[199] == [3.0, -4.0] and rows[200] == [0.0, 0.0]
    assert policy.peak_torque == 4.0


def test_interpolated_torques_run_linearly_between_knots():
    policy = TorquePolicy([[0.0], [1.0], [-1.0]], duration=2.0, mode='interpolated',
                          time_step=TIME_STEP)
    np.testing.assert_allclose(policy.knot_times, [0.0, 1.0, 2.0])
    np.testing.assert_allclose(policy.torque_at([0.0, 0.25, 1.0, 1.5, 1.995, 2.0]).ravel(),
                               [0.0, 0.25, 1.0, 0.0, -0.99, 0.0])


def test_gravity_compensation_holds_a_finger_still(finger):
    client, body, model = finger
    zero = np.zeros((2, model.num_joints))
    held = run(client, body, TorquePolicy(zero, 1.0, 'constant', True, TIME_STEP), 200)
    np.testing.assert_allclose(held, model.initial_angles, atol=1e-4)
    for index, angle in enumerate(model.initial_angles):
        client.resetJointState(body, index, angle, 0.0)
    dropped = run(client, body, TorquePolicy(zero, 1.0, 'constant', False, TIME_STEP), 200)
    assert np.max(np.abs(dropped - model.initial_angles)) > 0.1


@pytest.mark.parametrize('orientation', [PALM_UP, PALM_DOWN, TILTED],
                         ids=['palm up', 'palm down', 'tilted'])
def test_gravity_compensation_holds_a_turned_hand_still(client, orientation):
    body, model = build_finger(client, base_orientation=orientation)
    zero = np.zeros((2, model.num_joints))
    held = run(client, body, TorquePolicy(zero, 1.0, 'constant', True, TIME_STEP), 200)
    np.testing.assert_allclose(held, model.initial_angles, atol=1e-4)
    # the world's gravity is back after every call: an uncompensated finger falls
    assert client.getPhysicsEngineParameters()['gravityAccelerationZ'] == -9.81
    dropped = run(client, body, TorquePolicy(zero, 1.0, 'constant', False, TIME_STEP), 200)
    assert np.max(np.abs(dropped - model.initial_angles)) > 0.1
    for index, angle in enumerate(model.initial_angles):
        client.resetJointState(body, index, angle, 0.0)
    # a PD holding the initial angles needs no correction either
    policy = PDPolicy(targets=[model.initial_angles], keyframe_times=[1.0], kp=[1.0, 1.0],
                      kd=[1.0, 1.0], initial_angles=model.initial_angles, time_step=TIME_STEP)
    np.testing.assert_allclose(run(client, body, policy, 200), model.initial_angles,
                               atol=1e-4)


def test_pd_drives_the_joints_to_their_targets(finger):
    client, body, model = finger
    policy = PDPolicy(targets=[[0.5, -0.3], [-0.4, 0.6]], keyframe_times=[0.5, 1.0],
                      kp=[100.0, 100.0], kd=[20.0, 20.0], initial_angles=model.initial_angles,
                      time_step=TIME_STEP)
    halfway = run(client, body, policy, 100)  # tracking the first keyframe at t = 0.5
    np.testing.assert_allclose(halfway, [0.5, -0.3], atol=0.05)
    angles = run(client, body, policy, 400)  # restarts the track: ends holding keyframe 2
    np.testing.assert_allclose(angles, [-0.4, 0.6], atol=1e-3)
    assert policy.peak_torque == 0.0


@pytest.mark.parametrize('stable', [False, True], ids=['explicit', 'stable'])
def test_pd_torque_is_equation_one(finger, stable):
    """
    Check tau = M(q) a + C(q, qd) qd_d + N(q) with PyBullet's M(q).

    Explicit: a = -Kv edot - Kp e; stable: a = -(Kv edot + Kp (e + h edot)) / (1 + h Kv).
    """
    client, body, model = finger
    kp, kd = np.array([30.0, 50.0]), np.array([4.0, 7.0])
    policy = PDPolicy(targets=[[0.6, 0.3]], keyframe_times=[1.0], kp=kp, kd=kd,
                      initial_angles=model.initial_angles, time_step=TIME_STEP, stable=stable)
    torques = policy.start(client, body, 400)
    targets, target_velocities = policy.target_at([0.5])
    angles = np.array([0.45, -0.2])
    h = TIME_STEP if stable else 0.0

    def expected(velocities, coriolis_velocities):
        mass = np.array(client.calculateMassMatrix(body, angles.tolist()))
        error, error_rate = angles - targets[0], velocities - target_velocities[0]
        acceleration = -(kd * error_rate + kp * (error + h * error_rate)) / (1.0 + h * kd)
        # C(q, v) v + N(q) from inverse dynamics at zero acceleration
        bias = client.calculateInverseDynamics(body, angles.tolist(),
                                               coriolis_velocities.tolist(), [0.0, 0.0])
        return mass @ acceleration + np.array(bias)

    # joints moving exactly as the target: C(q, qd) qd_d = C(q, qd) qd
    for index in range(2):
        client.resetJointState(body, index, angles[index], target_velocities[0][index])
    np.testing.assert_allclose(torques(100), expected(target_velocities[0],
                                                      target_velocities[0]), rtol=1e-9)
    # after the last keyframe qd_d = 0: no Coriolis term for the actual velocity
    velocities = np.array([1.5, -2.0])
    for index in range(2):
        client.resetJointState(body, index, angles[index], velocities[index])
    targets, target_velocities = policy.target_at([1.5])
    np.testing.assert_allclose(target_velocities, 0.0)
    np.testing.assert_allclose(torques(300), expected(velocities, np.zeros(2)), rtol=1e-9)


def test_pd_targets_start_at_the_initial_angles():
    policy = PDPolicy(targets=[[1.0], [0.0]], keyframe_times=[0.5, 1.5], kp=[1.0], kd=[1.0],
                      initial_angles=[0.2], time_step=TIME_STEP)
    position, velocity = policy.target_at([0.0, 0.25, 0.5, 1.0, 1.5, 2.0])
    np.testing.assert_allclose(position.ravel(), [0.2, 0.6, 1.0, 0.5, 0.0, 0.0])
    np.testing.assert_allclose(velocity.ravel(), [1.6, 1.6, -1.0, -1.0, 0.0, 0.0])


def test_make_policy_follows_the_task_policy():
    spec = PolicySpec(kind='torque', duration=1.5, gravity_compensation=False,
                      mode='constant', knots=2)
    controller = ControllerDesign(kind='torque', values=np.array([[0.01, -0.02]] * 2))
    policy = make_policy(spec, controller, (0.0, 0.0), TIME_STEP)
    assert isinstance(policy, TorquePolicy)
    np.testing.assert_allclose(policy.knot_times, [0.0, 0.75])
    assert policy.peak_torque == 0.02
    pd = ControllerDesign(kind='pd', values=np.zeros((1, 2)), kp=np.ones(2), kd=np.ones(2))
    with pytest.raises(ValueError, match="controller kind 'pd' for a 'torque' policy"):
        make_policy(spec, pd, (0.0, 0.0), TIME_STEP)


# A finger of Tasks 1 and 2: 35 cm segments of 14 cm diameter, about 0.5 kg each.
LARGE_HAND = dataclasses.replace(HAND, base_position=(0.0, 0.0, 1.0), palm_size=(0.6, 0.1, 0.6),
                                 segment_radius=0.07, segment_density=100.0)


@pytest.mark.parametrize('kp', [1000.0, 5000.0])
def test_pd_at_table_one_highest_damping_tracks_where_explicit_saturates(client, kp):
    """Kv = 625 at dt = 0.005: explicit eq. (1) sits at Bullet's 100 rad/s cap, stable tracks."""
    body, model = build_finger(client, LARGE_HAND, (0.35, 0.35), PALM_UP)
    kd = 625.0
    targets = [[0.5, -0.3]]
    results = {}
    for stable in (False, True):
        for index, angle in enumerate(model.initial_angles):
            client.resetJointState(body, index, angle, 0.0)
        policy = PDPolicy(targets=targets, keyframe_times=[0.5], kp=[kp, kp], kd=[kd, kd],
                          initial_angles=model.initial_angles, time_step=TIME_STEP,
                          stable=stable)
        torques = policy.start(client, body, 200)
        errors, speeds = [], []
        for step in range(200):
            client.setJointMotorControlArray(body, [0, 1], client.TORQUE_CONTROL,
                                             forces=torques(step))
            client.stepSimulation()
            states = client.getJointStates(body, [0, 1])
            target, _ = policy.target_at([(step + 1) * TIME_STEP])
            errors.append(np.array([state[0] for state in states]) - target[0])
            speeds.append([state[1] for state in states])
        results[stable] = np.abs(errors), np.abs(speeds)
    errors, speeds = results[False]
    assert np.mean(speeds.max(axis=1) >= 99.0) > 0.9  # at the cap nearly all the time
    assert errors[-1].max() > 0.1
    errors, speeds = results[True]
    assert speeds.max() < 5.0  # the ramp runs at about 1 rad/s
    assert errors.max() < 0.01  # on the ramp (velocity feed-forward) and after
    assert errors[-1].max() < 1e-3
