"""MuJoCo, the second engine: the same model, the same scene behaviour, deterministic results."""

import dataclasses
import pathlib
import types

from hand_codesign.analysis.replay import rollout_poses
from hand_codesign.core import genome_spec, load_task, Simulator, world_states
from hand_codesign.core.design import ControllerDesign, FingerDesign, JointDesign
from hand_codesign.core.evaluate import evaluate, evaluate_design
from hand_codesign.core.sim.geometry import link_frames
from hand_codesign.core.sim.hand import hand_model
from hand_codesign.core.sim.mujoco_sim import (_geom_size, ARENA_BYTES, hand_spec, MujocoSimulator,
                                               object_inertia)
from hand_codesign.core.sim.objectives import COLLISION_PENALTY, goal_schedule
from hand_codesign.core.sim.policies import make_policy
from hand_codesign.core.sim.worlds import object_state, WorldState
import mujoco
import numpy as np
import pytest

TASKS = pathlib.Path(__file__).resolve().parents[3] / 'config' / 'tasks'
ENGINES = (Simulator, MujocoSimulator)


@pytest.fixture(scope='module')
def task():
    return load_task(TASKS / 'task5.yaml').replace(num_world_states=4)


def on_mujoco(task):
    return task.replace(physics=dataclasses.replace(task.physics, engine='mujoco'))


def fingers_design(task, angle=0.0, lengths=(0.04, 0.04), limit=1.2, torques=None):
    """Return a Task 5 design: fingers at x = -+5.5 cm turned outwards by `angle`."""
    fingers = tuple(FingerDesign(
        position=(x, 0.0), segment_lengths=lengths,
        joints=(JointDesign(axis_angle=np.pi / 2, initial_angle=turn, lower_limit=-limit,
                            upper_limit=limit),) * 2)
        for x, turn in ((-0.055, angle), (0.055, -angle)))
    base = genome_spec(task).decode(genome_spec(task).initial_mean())
    values = np.zeros((2, 4)) if torques is None else np.array([torques] * 2, dtype=float)
    return dataclasses.replace(base, hand=dataclasses.replace(base.hand, fingers=fingers),
                               controller=ControllerDesign(kind='torque', values=values))


def joint_angles(simulator):
    if simulator.engine == 'mujoco':
        return simulator.joint_states()[0]
    joints = list(range(simulator.model.num_joints))
    return [state[0] for state in simulator.client.getJointStates(simulator.hand, joints)]


def nominal_rollout(engine, task, design):
    """Run the nominal world; return the Rollout and the joint angles of every step."""
    model = hand_model(design.hand, task.hand)
    state = object_state(task, WorldState.nominal())
    angles = []
    with engine() as simulator:
        simulator.build(task, model)
        policy = make_policy(task.policy, design.controller, model.initial_angles,
                             task.time_step)
        result = simulator.rollout(state, simulator.object_shape(state, 'box'), policy,
                                   goal_schedule(task),
                                   on_frame=lambda step, s: angles.append(joint_angles(s)))
    return result, np.array(angles)


def test_masses_inertias_and_link_frames_are_those_of_pybullet(task):
    design = fingers_design(task, angle=0.3, lengths=(0.05, 0.035))
    model = hand_model(design.hand, task.hand)
    state = object_state(task, WorldState((0.0, 0.0, 0.0), 0.2, 0.05, 1.3, 0.8))
    with Simulator() as bullet, MujocoSimulator() as mj:
        bullet.build(task, model)
        mj.build(task, model)
        mj.reset(state, 'box')
        m, d = mj.mj_model, mj.mj_data
        mujoco.mj_kinematics(m, d)
        for index, link in enumerate(model.links):
            info = bullet.client.getDynamicsInfo(bullet.hand, index)
            body = m.body(link.name).id
            assert m.body_mass[body] == pytest.approx(info[0], rel=1e-12)
            np.testing.assert_allclose(m.body_inertia[body], info[2], rtol=1e-12)
            frame = bullet.client.getLinkState(bullet.hand, index)
            np.testing.assert_allclose(d.xpos[body], frame[4], atol=1e-12)
            x, y, z, w = frame[5]
            assert abs(np.dot(d.xquat[body], (w, x, y, z))) == pytest.approx(1.0, abs=1e-7)
        box = bullet.create_object(state, bullet.object_shape(state, 'box'))
        info = bullet.client.getDynamicsInfo(box, -1)
        assert m.body_mass[m.body('object').id] == pytest.approx(info[0], rel=1e-12)
        np.testing.assert_allclose(m.body_inertia[m.body('object').id], info[2], rtol=1e-9)


def test_a_joint_held_at_its_limit_passes_it_by_less_than_a_milliradian(task):
    # every joint pushed outwards (away from the box) onto its limit of 0.3 rad for 1.5 s
    design = fingers_design(task, limit=0.3, torques=[0.01, 0.005, -0.01, -0.005])
    for engine in ENGINES:
        _, angles = nominal_rollout(engine, task, design)
        held = angles[len(angles) // 2:]  # the second half: held against the limits
        np.testing.assert_allclose(np.abs(held), 0.3, atol=1e-3, err_msg=engine.engine)


def test_a_box_at_rest_sits_at_the_same_height_in_both_engines(task):
    design = fingers_design(task)  # short fingers hanging straight down, far above the box
    heights = [nominal_rollout(engine, task, design)[0].final_position[2] for engine in ENGINES]
    assert abs(heights[0] - heights[1]) < 2e-4
    assert abs(heights[1] - 0.02) < 2e-4  # the box's resting height


def test_gravity_compensation_holds_a_hand_still(task):
    still = task.replace(policy=dataclasses.replace(task.policy, gravity_compensation=True))
    design = fingers_design(task, angle=0.5)  # fingers raised sideways, no torque
    _, angles = nominal_rollout(MujocoSimulator, on_mujoco(still), design)
    np.testing.assert_allclose(np.abs(angles), 0.5, atol=1e-6)
    _, falling = nominal_rollout(MujocoSimulator, on_mujoco(task), design)
    assert np.abs(np.abs(falling) - 0.5).max() > 0.1


def test_start_collision_verdicts_agree_with_pybullet(task):
    spec = genome_spec(task)
    generator = np.random.default_rng(3)
    states = [object_state(task, world) for world in world_states(task, 8)]
    verdicts = {engine.engine: [] for engine in ENGINES}
    for _ in range(40):
        model = hand_model(spec.decode(generator.random(len(spec.lower))).hand, task.hand)
        for engine in ENGINES:
            with engine() as simulator:
                simulator.build(task, model)
                objects = [(state, simulator.object_shape(state, 'box')) for state in states]
                verdicts[engine.engine].append(simulator.start_collisions(objects))
    assert verdicts['pybullet'] == verdicts['mujoco']
    assert 5 <= sum(verdicts['mujoco']) <= 35  # both verdicts occur


def test_evaluations_on_mujoco_are_deterministic_in_any_order(task):
    mj = on_mujoco(task)
    design = fingers_design(task, angle=0.2, lengths=(0.06, 0.06),
                            torques=[-0.006, -0.004, 0.008, 0.003])
    first = evaluate_design(design, mj)
    assert not first.collision and first.simulated_time > 0
    evaluate(genome_spec(mj).initial_mean(), mj)  # another candidate in between
    again = evaluate_design(design, mj)
    np.testing.assert_array_equal(first.objectives, again.objectives)
    np.testing.assert_array_equal(first.final_poses, again.final_poses)
    backwards = evaluate_design(design, mj, worlds=world_states(mj)[::-1])
    np.testing.assert_array_equal(backwards.world_objectives, first.world_objectives[::-1])
    assert not np.array_equal(first.final_poses, evaluate_design(design, task).final_poses)


def test_a_design_starting_in_the_ground_collides_on_mujoco(task):
    straight = fingers_design(task, lengths=(0.09, 0.09))  # reaches below z = 0
    result = evaluate_design(straight, on_mujoco(task))
    assert result.collision
    np.testing.assert_array_equal(result.objectives, [COLLISION_PENALTY] * 2)
    assert result.simulated_time == 0.0


@pytest.mark.parametrize('preset', sorted(path.name for path in TASKS.glob('*.yaml')))
def test_every_preset_runs_on_mujoco(preset):
    task = on_mujoco(load_task(TASKS / preset).replace(num_world_states=2))
    spec = genome_spec(task)
    generator = np.random.default_rng(2)
    # the first of a few designs around the search's start that does not start in collision
    result = next(result for result in (
        evaluate(np.clip(spec.initial_mean() + 0.1 * generator.normal(size=spec.size), 0, 1),
                 task) for _ in range(30)) if not result.collision)
    assert result.simulated_time > 0 and np.all(np.isfinite(result.objectives))


def test_open_loop_torques_stepped_in_c_are_the_steps_one_at_a_time(task):
    design = fingers_design(task, angle=0.2, lengths=(0.06, 0.06),
                            torques=[-0.006, -0.004, 0.008, 0.003])
    mj = on_mujoco(task)
    with MujocoSimulator() as chunked, MujocoSimulator() as single:
        single.chunked = False
        results = [evaluate_design(design, mj, simulator=simulator)
                   for simulator in (chunked, single)]
    assert results[0].simulated_time > 0
    np.testing.assert_array_equal(results[0].world_objectives, results[1].world_objectives)
    np.testing.assert_array_equal(results[0].final_poses, results[1].final_poses)


def test_replay_poses_of_a_mujoco_run_are_mujoco_s(task):
    mj = on_mujoco(task)
    spec = genome_spec(mj)
    generator = np.random.default_rng(4)
    x = next(x for x in (np.clip(spec.initial_mean() + 0.1 * generator.normal(size=spec.size),
                                 0, 1) for _ in range(30)) if not evaluate(x, mj).collision)
    world = world_states(mj)[0]
    model, palm, frames = rollout_poses(mj, types.SimpleNamespace(x=x), world)
    final = evaluate(x, mj, worlds=[world]).final_poses[0]
    # the object rests at the end: the last frame, a few steps before, is where it ends
    np.testing.assert_allclose(np.concatenate(frames[-1][2]), final, atol=1e-9)
    _, _, bullet = rollout_poses(task, types.SimpleNamespace(x=x), world)
    assert not np.allclose(np.concatenate(bullet[-1][2]), final, atol=1e-6)
    for (position, _), (expected, _) in zip(frames[0][1], link_frames(model, palm)):
        np.testing.assert_allclose(position, expected, atol=1e-12)


def worlds_written(preset):
    """
    Yield (task, model, simulator, state) for three worlds of a preset, in MuJoCo.

    The preset's initial design is built once; each world is written over the one before
    (turned and moved off the nominal start).
    """
    task = on_mujoco(load_task(TASKS / preset))
    spec = genome_spec(task)
    model = hand_model(spec.decode(spec.initial_mean()).hand, task.hand)
    with MujocoSimulator() as simulator:
        simulator.build(task, model)
        for world in world_states(task, 3):
            state = object_state(task, world)
            simulator.reset(state, task.object_spec.shape)
            yield task, model, simulator, state


@pytest.mark.parametrize('preset', ['task1.yaml', 'task2.yaml', 'task5.yaml'])  # each shape
def test_a_world_written_into_the_model_is_the_model_compiled_for_it(preset):
    for task, model, simulator, state in worlds_written(preset):
        shape = task.object_spec.shape
        compiled = hand_spec(model, task.time_step, task.hand.base_position,
                             task.hand.base_orientation, shape,
                             task.policy.gravity_compensation)
        compiled.memory = ARENA_BYTES
        compiled.geom('object').size = list(_geom_size(shape, state.size)[0])
        compiled.geom('object').friction = [model.friction * state.friction, 0.0, 0.0]
        compiled.pair('object_ground').friction = [state.friction] * 2 + [0.0] * 3
        body = compiled.body('object')
        body.mass = state.mass
        body.inertia = list(object_inertia(shape, state.size, state.mass))
        body.pos = list(state.position)
        x, y, z, w = state.orientation
        body.quat = [w, x, y, z]
        expected, written = compiled.compile(), simulator.mj_model
        for name in dir(expected):
            value = getattr(expected, name)
            if isinstance(value, np.ndarray):
                np.testing.assert_array_equal(getattr(written, name), value, err_msg=name)
        for name in ('meaninertia', 'meanmass', 'extent'):  # meansize: drawings only
            assert getattr(written.stat, name) == getattr(expected.stat, name), name


@pytest.mark.parametrize('preset', ['task1.yaml', 'task2.yaml', 'task5.yaml'])  # each shape
def test_the_object_s_centre_of_mass_and_inertia_axes_are_its_shape_s(preset):
    for task, model, simulator, state in worlds_written(preset):
        m, d = simulator.mj_model, simulator.mj_data
        mujoco.mj_kinematics(m, d)
        body, geom = simulator._object_body, simulator._object_geom
        np.testing.assert_allclose(d.xipos[body], d.geom_xpos[geom], atol=1e-12)
        np.testing.assert_allclose(d.xipos[body], state.position, atol=1e-12)
        np.testing.assert_allclose(d.ximat[body], d.geom_xmat[geom], atol=1e-12)


def test_a_hand_object_contact_is_read_within_a_millimetre_but_acts_only_when_touching(task):
    # MuJoCo 4 activates a contact within its margin and only detects it within margin + gap:
    # the object's margin is 0, so a finger 0.5 mm off the box is a touch that exerts nothing
    task = on_mujoco(task)
    design = fingers_design(task)
    model = hand_model(design.hand, task.hand)
    state = object_state(task, WorldState.nominal())
    with MujocoSimulator() as simulator:
        simulator.build(task, model)
        simulator.reset(state, 'box')
        m, d = simulator.mj_model, simulator.mj_data
        finger = m.geom(model.links[1].name).id  # the first finger's tip segment
        start = simulator._object_qpos
        apart = np.zeros(6)
        mujoco.mj_forward(m, d)
        distance = mujoco.mj_geomDistance(m, d, simulator._object_geom, finger, 1.0, apart)
        towards = (apart[3:] - apart[:3]) / distance  # from the box to the finger
        simulator.object_body = simulator._object_body
        for gap, acts in ((0.0005, False), (-0.0005, True)):
            d.qpos[start:start + 3] += towards * (distance - gap)
            mujoco.mj_forward(m, d)
            contacts = [contact for contact in d.contact[:d.ncon] if finger in contact.geom]
            assert len(contacts) >= 1 and all(
                abs(contact.dist - gap) < 1e-6 for contact in contacts), gap
            assert all((contact.efc_address >= 0) == acts for contact in contacts), gap
            assert 1 in simulator.touching_links(0.001)
            distance = gap


def test_a_box_on_the_ground_and_joints_on_their_limits_are_held_from_the_first_step(task):
    # MuJoCo's constraints act only within their margin: with margin 0, a box starting on the
    # ground fell freely for one step (0.25 mm) and a joint pushed onto the limit it starts on
    # passed it by tens of mrad before being pushed back; Bullet holds both from the start
    design = fingers_design(task, angle=0.3, limit=0.3, torques=[0.01, 0.005, -0.01, -0.005])
    for engine in ENGINES:
        _, angles = nominal_rollout(engine, task, design)
        assert np.abs(angles).max() < 0.3 + 1e-3, engine.engine
    model = hand_model(design.hand, task.hand)
    state = object_state(task, WorldState.nominal())
    with MujocoSimulator() as simulator:
        simulator.build(on_mujoco(task), model)
        simulator.reset(state, 'box')
        mujoco.mj_step(simulator.mj_model, simulator.mj_data)
        assert abs(simulator.object_pose()[0][2] - state.position[2]) < 1e-5
