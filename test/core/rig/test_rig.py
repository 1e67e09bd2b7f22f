"""
Hardware in the loop without ROS: physical designs, the simulated rig and the trial protocol.

A candidate's physical fields rebuild its Design bit for bit; a rig that measures every
physics step scores exactly what `evaluate` computes; sampled at 100 Hz off the checks, within
the interpolation tolerance that core.rig.trials derives; timeouts, failures and lost tracking
reject a candidate with the reason, and a start collision charges the collision penalty.
"""

import dataclasses
import pathlib
import xml.etree.ElementTree as ElementTree

from hand_codesign.core import evaluate, genome_spec, load_task
from hand_codesign.core.rig.simulated import SampleClock, SimulatedRig
from hand_codesign.core.rig.trials import interpolation_tolerance, pose_at, RigTrials, TrackingLost
from hand_codesign.core.sim.objectives import COLLISION_PENALTY
from hand_codesign.core.sim.physical import candidate_design, design_from_physical
import numpy as np
import pytest

TASKS = pathlib.Path(__file__).resolve().parents[3] / 'config' / 'tasks'
START = 5_000_000_000  # ns: a rig clock's stamp of every trial's start


def genomes(task, count, seed):
    spec = genome_spec(task)
    generator = np.random.default_rng(seed)
    return [spec.initial_mean() + 0.2 * generator.normal(size=spec.size) for _ in range(count)]


def rebuilt(task, x):
    physical = candidate_design(task, x)
    return design_from_physical(task.structure, physical.names, physical.values,
                                physical.controller_kind, physical.controller_values,
                                physical.kp, physical.kd)


def rig_evaluation(task, x, clock=SampleClock(), engine='', **limits):
    """Return the outcome of RigTrials on a SimulatedRig, as the nodes exchange it."""
    design = rebuilt(task, x)
    rig = SimulatedRig(clock, engine=engine)
    trials = RigTrials(task, design, **limits)
    try:
        while True:
            action = trials.poll(0.0)
            if action[0] != 'request':
                return action, trials
            _, trial_id, spec = action
            poses = []
            outcome = rig.run(task, design, spec, lambda t, p, q: poses.append((t, p, q)))
            if outcome == 'collision':
                trials.collided(trial_id)
                continue
            for t, position, orientation in poses:   # the poses may overtake the start
                trials.pose(START + round(t * 1e9), position, orientation)
            trials.started(trial_id, START)
            trials.ended(trial_id, START + round(poses[-1][0] * 1e9), 0.0)
    finally:
        rig.close()


@pytest.mark.parametrize('preset', ['task5.yaml', 'task5_pd.yaml'])
def test_physical_fields_rebuild_the_decoded_design(preset):
    task = load_task(TASKS / preset).replace(num_world_states=2)
    for x in genomes(task, 3, 1):
        assert rebuilt(task, x) == genome_spec(task).decode(x)


def test_hand_urdf_is_standard_urdf_with_every_joint():
    task = load_task(TASKS / 'task5.yaml')
    physical = candidate_design(task, genomes(task, 1, 2)[0])
    robot = ElementTree.fromstring(physical.urdf)
    assert robot.tag == 'robot'
    assert not robot.findall('.//capsule')
    assert robot.findall('.//cylinder') and robot.findall('.//sphere')
    assert len(robot.findall('joint')) == sum(task.structure)
    assert len(physical.names) == len(physical.values)
    assert len(physical.controller_values) == task.policy.num_knots * sum(task.structure)


def test_every_step_measured_gives_the_simulated_objectives_exactly():
    task = load_task(TASKS / 'task5.yaml').replace(num_world_states=3)
    collisions = 0
    for x in genomes(task, 4, 1):
        action, _ = rig_evaluation(task, x)
        simulated = evaluate(x, task)
        assert action[0] == 'evaluated'
        assert action[1].collision == simulated.collision
        collisions += simulated.collision
        np.testing.assert_array_equal(action[1].objectives, simulated.objectives)
        np.testing.assert_array_equal(action[1].world_objectives, simulated.world_objectives)
    assert 0 < collisions < 4   # both outcomes were compared


def test_a_rig_on_the_other_engine_measures_that_engine_s_physics():
    task = load_task(TASKS / 'task5.yaml').replace(num_world_states=3)
    on_mujoco = task.replace(physics=dataclasses.replace(task.physics, engine='mujoco'))
    x = next(x for x in genomes(task, 6, 1) if not evaluate(x, task).collision)
    action, _ = rig_evaluation(task, x, engine='mujoco')  # a PyBullet run, a MuJoCo rig
    assert action[0] == 'evaluated'
    np.testing.assert_array_equal(action[1].objectives, evaluate(x, on_mujoco).objectives)
    assert not np.array_equal(action[1].objectives, evaluate(x, task).objectives)


def test_sampled_at_100_hz_within_the_derived_tolerance():
    task = load_task(TASKS / 'task1.yaml').replace(num_world_states=2)
    # the first of a few designs that does not start in collision
    x, simulated = next((x, result) for x in genomes(task, 6, 1)
                        for result in [evaluate(x, task)] if not result.collision)
    # samples halfway between the physics steps of the checks: every check is interpolated
    action, trials = rig_evaluation(task, x, SampleClock(rate=100.0, phase=0.5))
    assert action[0] == 'evaluated'
    tolerance = np.max([interpolation_tolerance(trials.schedule, *trace)
                        for trace in action[2]], axis=0)
    position = np.array([name.startswith('position') for name in task.objective_names])
    bound = np.where(position, tolerance[0], tolerance[1])
    gap = np.abs(action[1].objectives - simulated.objectives)
    assert np.all(gap <= bound)
    assert gap.max() > 0      # the poses really were interpolated
    assert bound.max() < 0.01  # and the bound says something: under 1 cm, 0.01 rad


def test_pose_between_samples_is_interpolated_and_a_gap_loses_tracking():
    times = np.array([0.0, 0.01, 0.2])
    positions = np.array([[0.0, 0, 0], [0.01, 0, 0], [0.2, 0, 0]])
    turn = np.sin(0.05), np.cos(0.05)   # 0.1 rad about z
    orientations = np.array([[0, 0, 0, 1.0], [0, 0, turn[0], turn[1]], [0, 0, 0, 1.0]])
    position, orientation = pose_at(times, positions, orientations, 0.005)
    np.testing.assert_allclose(position, [0.005, 0, 0])
    np.testing.assert_allclose(orientation, [0, 0, np.sin(0.025), np.cos(0.025)])
    assert pose_at(times, positions, orientations, 0.01 + 1e-9)[0] == tuple(positions[1])
    with pytest.raises(TrackingLost, match='tracking lost from t = 0.0100 to 0.2000 s'):
        pose_at(times, positions, orientations, 0.1)
    with pytest.raises(TrackingLost, match='no pose measured after'):
        pose_at(times, positions, orientations, 0.3)


@pytest.fixture(scope='module')
def task5():
    return load_task(TASKS / 'task5.yaml').replace(num_world_states=2)


def started_trials(task, clock_now=0.0):
    trials = RigTrials(task, rebuilt(task, genomes(task, 1, 3)[0]), start_timeout=5.0,
                       end_margin=5.0, settle=1.0)
    kind, trial_id, spec = trials.poll(clock_now)
    assert kind == 'request' and spec.world == 0 and spec.worlds == 2
    return trials, trial_id, spec


def test_a_rig_that_does_not_start_or_end_in_time_is_a_rejection(task5):
    trials, trial_id, spec = started_trials(task5)
    assert trials.poll(4.9) is None
    assert trials.poll(5.1) == ('rejected', f'timeout: the rig did not start trial {trial_id} '
                                            '(world 0) within 5.0 s')
    trials, trial_id, spec = started_trials(task5)
    trials.started(trial_id, START)
    assert trials.poll(10.0 + spec.duration - 0.1) is None
    assert trials.poll(10.0 + spec.duration + 0.1)[1].startswith('timeout: trial')


def test_lost_tracking_and_failures_are_rejections_and_a_collision_is_penalized(task5):
    trials, trial_id, spec = started_trials(task5)
    trials.started(trial_id, START)
    trials.pose(START, spec.position, spec.orientation)   # the first pose only
    trials.ended(trial_id, START + int(spec.duration * 1e9), 1.0)
    assert trials.poll(1.5) is None    # waiting for poses still in flight
    kind, reason = trials.poll(2.1)
    assert kind == 'rejected' and reason.startswith('world 0: no pose measured after')
    trials, trial_id, _ = started_trials(task5)
    trials.failed(trial_id, 'object dropped while placing it')
    assert trials.poll(0.1) == ('rejected', 'the rig failed: object dropped while placing it')
    trials, trial_id, _ = started_trials(task5)
    trials.collided(trial_id + 1)      # another trial's event changes nothing
    assert trials.poll(0.1) is None
    trials.collided(trial_id)
    kind, evaluation, _ = trials.poll(0.1)
    assert kind == 'evaluated' and evaluation.collision
    assert np.all(evaluation.objectives == COLLISION_PENALTY)


def test_rig_noise_is_seeded_and_moves_the_measured_poses():
    task = load_task(TASKS / 'task5.yaml').replace(num_world_states=1)
    x = genomes(task, 1, 1)[0]
    design = rebuilt(task, x)
    spec = RigTrials(task, design).poll(0.0)[2]

    def trace(noise, seed):
        rig = SimulatedRig(SampleClock(rate=100.0), noise, seed)
        poses = []
        try:
            assert rig.run(task, design, spec, lambda t, p, q: poses.append((t, *p, *q))) == 'ok'
        finally:
            rig.close()
        return np.array(poses)

    exact, noisy = trace((0.0, 0.0), 0), trace((0.001, 0.01), 3)
    assert exact.shape == noisy.shape and exact.shape[0] == 151   # 100 Hz over 1.5 s
    np.testing.assert_array_equal(noisy, trace((0.001, 0.01), 3))
    assert 0.0003 < np.std(noisy[:, 1:4] - exact[:, 1:4]) < 0.003
    np.testing.assert_allclose(np.linalg.norm(noisy[:, 4:], axis=1), 1.0)
