"""Outcome descriptors: measured in evaluate's rollouts as core.experiments.measures does."""

import dataclasses

from hand_codesign.core.evaluate import evaluate, evaluate_design
from hand_codesign.core.experiments.measures import frame_interval, measure_worlds
from hand_codesign.core.outcomes import Answer, CONTACT_DISTANCE, OutcomeWatch, task_outcomes
from hand_codesign.core.rotations import axis_angle_quaternion, quaternion_multiply, vertical_turn
from hand_codesign.core.sim.objectives import goal_schedule
from hand_codesign.core.sim.worlds import object_state, world_states
from hand_codesign.core.task.genome import genome_spec
from hand_codesign.core.task.parts import ArchiveSpec
import numpy as np
import pytest
from test_sim import design, task, with_fingers  # noqa: F401 - fixtures of the Task 5 scene


@pytest.fixture(scope='module')
def outcome_task(task):  # noqa: F811 - test_sim's fixture
    """Return Task 5 (4 worlds) searched by CMA-MAE over both outcome descriptors."""
    return task.replace(algorithm='cma-mae',
                        archive=ArchiveSpec(descriptors=('limit_rest', 'touch')))


def genomes(task, count):  # noqa: F811
    """Return genomes drawn over the whole bounds (about half of them start in collision)."""
    spec = genome_spec(task)
    return np.random.default_rng(3).uniform(0, 1, (count, spec.size))


def touching_at_the_end(task, design):  # noqa: F811
    """Return per world whether a contact point joins hand and object at the last frame."""
    flags = {}
    state = {'world': 0}

    def on_world(index, simulator):
        state['world'] = index

    def on_frame(step, simulator):
        points = simulator.client.getContactPoints(simulator.hand, simulator.object_body)
        flags[state['world']] = any(point[8] <= CONTACT_DISTANCE for point in points)

    evaluate_design(design, task, on_world=on_world, on_frame=on_frame,
                    frame_every=frame_interval(goal_schedule(task)))
    # a design that starts in collision is not simulated: it touches nothing
    return np.array([flags.get(index, False) for index in range(task.num_world_states)])


def test_only_a_task_whose_archive_names_them_measures_outcomes(task, outcome_task):  # noqa
    assert task_outcomes(task) == ()
    assert task_outcomes(outcome_task) == ('limit_rest', 'touch')
    mixed = task.replace(algorithm='cma-me',
                         archive=ArchiveSpec(descriptors=('limit_rest', 'joint_range')))
    assert task_outcomes(mixed) == ('limit_rest',)
    x = genomes(task, 1)[0]
    plain = evaluate(x, task)
    assert plain.outcome_names == () and plain.outcomes.shape == (0,)


@pytest.mark.system  # a long physics run (a minute or more here)
def test_outcome_shares_are_what_measures_finds_and_change_no_objective(task, outcome_task):  # noqa
    worlds = world_states(outcome_task)
    spec = genome_spec(outcome_task)
    shares = []
    for x in genomes(outcome_task, 20):
        evaluation = evaluate(x, outcome_task)
        assert evaluation.outcome_names == ('limit_rest', 'touch')
        if evaluation.collision:  # nothing simulated (measures simulates the other worlds)
            assert evaluation.outcomes.tolist() == [0.0, 0.0]
            continue
        measured = measure_worlds(x, outcome_task, worlds)
        touching = touching_at_the_end(outcome_task, spec.decode(x))
        assert evaluation.outcomes.tolist() == [np.mean(measured.limit_contacts),
                                                np.mean(touching)]
        # reading the scene at the end changes nothing of the evaluation
        plain = evaluate(x, task)
        for name in ('objectives', 'world_objectives', 'final_poses', 'final_errors'):
            assert getattr(plain, name).tobytes() == getattr(evaluation, name).tobytes(), name
        assert plain.simulated_time == evaluation.simulated_time
        shares.append(evaluation.outcomes)
    shares = np.array(shares)
    assert len(shares) >= 6
    assert ((shares >= 0) & (shares <= 1)).all()
    assert (shares[:, 0] <= shares[:, 1]).all()  # resting on a limit while touching is a touch
    # the designs differ in their outcomes, and touching is not always resting on a limit
    assert len({tuple(row) for row in shares}) > 2 and (shares[:, 0] < shares[:, 1]).any()


def test_a_design_starting_in_collision_has_no_outcome(outcome_task, design):  # noqa: F811
    straight = with_fingers(design, lengths=(0.09, 0.09), angle=0.0)  # reaches below z = 0
    evaluation = evaluate_design(straight, outcome_task)
    assert evaluation.collision and evaluation.outcomes.tolist() == [0.0, 0.0]


def test_vertical_turn_is_the_twist_about_z_whatever_the_tilt():
    tilt = axis_angle_quaternion((1.0, 0.0, 0.0), 0.4)
    start = axis_angle_quaternion((0.0, 1.0, 0.0), 0.3)
    for angle in (0.0, 0.7, -1.2, 3.0):
        yaw = axis_angle_quaternion((0.0, 0.0, 1.0), angle)
        assert vertical_turn(start, quaternion_multiply(yaw, start)) == pytest.approx(angle)
    assert vertical_turn(start, quaternion_multiply(tilt, start)) == pytest.approx(0.0)
    # three quarters of a turn one way is a quarter the other way
    yaw = axis_angle_quaternion((0.0, 0.0, 1.0), 1.5 * np.pi)
    assert vertical_turn(start, quaternion_multiply(yaw, start)) == pytest.approx(-np.pi / 2)


def test_the_turn_outcome_is_the_mean_turn_of_the_final_poses(task, design):  # noqa: F811
    turning = task.replace(algorithm='cma-mae',
                           archive=ArchiveSpec(descriptors=('turn', 'finger_length')))
    assert task_outcomes(turning) == ('turn',)
    evaluation = evaluate_design(design, turning)
    assert not evaluation.collision and evaluation.unstable_worlds == 0
    starts = [object_state(turning, world).orientation for world in world_states(turning)]
    turns = [abs(vertical_turn(start, pose[3:])) / np.pi
             for start, pose in zip(starts, evaluation.final_poses)]
    assert evaluation.outcomes[0] == pytest.approx(np.mean(turns), abs=1e-9)
    assert 0 < evaluation.outcomes[0] < 1  # the design pushes the box: it turns a little
    plain = evaluate_design(design, task)
    assert plain.objectives.tobytes() == evaluation.objectives.tobytes()


def test_an_unstable_world_counts_as_neither():
    watch = OutcomeWatch(('limit_rest', 'touch'), [None, None])
    unstable = dataclasses.make_dataclass('Rollout', ['unstable'])(True)
    watch.on_end(0)(None, unstable)  # the scene is never read
    assert watch.shares().tolist() == [0.0, 0.0]
    assert OutcomeWatch((), [None] * 3).on_end(0) is None


def test_answers_agree_only_when_objectives_and_outcomes_agree_bit_for_bit():
    first = Answer.of([0.1, 0.2], ('limit_rest',), [0.5])
    assert first.fingerprint() == Answer.of((0.1, 0.2), ['limit_rest'], (0.5,)).fingerprint()
    assert first.fingerprint() != Answer.of([0.1, 0.2], ('limit_rest',), [0.25]).fingerprint()
    assert first.fingerprint() != Answer.of([0.1, 0.2], ('touch',), [0.5]).fingerprint()
    assert first.fingerprint() != Answer.of([0.1, 0.2]).fingerprint()
