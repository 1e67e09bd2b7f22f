"""
core.experiments.measures on small real rollouts: motions, the pose error, joint limits found.

What a campaign reports of a design must not read better than the rollout it measures: a
world is read at the end of the whole motion (never where early termination stopped it),
Task 4's success needs the position and the turn at once, and "joint limits found" needs the
box within tolerance on a limit the joint reached (not one it started on).
"""

import dataclasses
import json
import math
import pathlib

from hand_codesign.analysis import unseen
from hand_codesign.campaign import folders
from hand_codesign.campaign import measures as campaign_measures
from hand_codesign.core.design import (ControllerDesign, Design, FingerDesign, HandDesign,
                                       JointDesign)
from hand_codesign.core.evaluate import _TaskContext, evaluate_design
from hand_codesign.core.experiments.measures import (LIMITS_FOUND_MIN_SHARE, LIMITS_FOUND_SHARE,
                                                     measure_worlds, ORIENTATION_01, PLANE_5MM,
                                                     POSE, summarize, unseen_world_states,
                                                     with_pose_error, WorldMeasures)
from hand_codesign.core.outcomes import fingers, LIMIT_TOLERANCE
from hand_codesign.core.task import load_task
from hand_codesign.core.task.genome import genome_spec
import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]
TASK3 = ROOT / 'config' / 'reproduce' / 'task3.yaml'
TASK5 = ROOT / 'config' / 'reproduce' / 'task5.yaml'


def test_unseen_worlds_are_read_at_the_end_of_the_whole_motion():
    # Task 3 follows a pose trajectory with early termination (eq. 6); a random design misses
    # its goals, so training rollouts stop at an early check
    stopping = load_task(TASK3).replace(seed=3, num_world_states=2)
    assert stopping.early_termination is not None
    full = stopping.replace(early_termination=None)
    worlds = unseen_world_states(stopping, 2)
    generator = np.random.default_rng(5)
    while True:
        x = generator.random(len(genome_spec(full).names))
        whole = evaluate_design(_TaskContext.of(full).genome_spec().decode(x), full, worlds)
        if not whole.collision:
            break
    measured = measure_worlds(x, stopping, worlds)
    cut = evaluate_design(_TaskContext.of(stopping).genome_spec().decode(x), stopping, worlds)
    assert cut.simulated_time < whole.simulated_time
    np.testing.assert_array_equal(measured.errors['orientation'], whole.final_errors[:, 1])
    np.testing.assert_array_equal(measured.errors['position'], whole.final_errors[:, 0])
    # the stopped rollouts end elsewhere: reading them would change the measure
    assert not np.array_equal(cut.final_poses, whole.final_poses)


def test_the_pose_error_needs_the_position_and_the_turn_at_once():
    task = load_task(TASK5).replace(seed=2)
    x = np.random.default_rng(1).random(len(genome_spec(task).names))
    measured = measure_worlds(x, task, unseen_world_states(task, 6))
    both = (measured.errors['plane'] < 0.005) & (measured.errors['orientation'] < 0.1)
    np.testing.assert_array_equal(measured.errors['pose'] < 1.0, both)
    # worlds that pass one check and not the other: within the turn, outside the plane
    errors = {'plane': np.array([0.001, 0.009, 0.004, 0.02]),
              'orientation': np.array([0.05, 0.05, 0.2, 0.3])}
    worlds = _world_measures(errors, limit_reached=[False] * 4)
    assert summarize(worlds, POSE).within == 0.25
    assert summarize(worlds, ORIENTATION_01).within == 0.5
    assert summarize(worlds, PLANE_5MM).within == 0.5
    assert 'and orientation error < 0.1 rad' in POSE.describe()


def _world_measures(errors, limit_reached, limit_contacts=None, collisions=None):
    count = len(limit_reached)
    errors = with_pose_error({kind: np.asarray(values, dtype=float)
                              for kind, values in errors.items()})
    return WorldMeasures(
        errors, errors, np.zeros(count, bool) if collisions is None else np.array(collisions),
        np.array(limit_reached if limit_contacts is None else limit_contacts, dtype=bool),
        np.array(limit_reached, dtype=bool))


def test_joint_limits_are_found_only_where_the_box_ends_within_tolerance():
    within = [0.05, 0.05, 0.05, 0.05, 0.5, 0.5, 0.5, 0.5]  # rad: four successes, four fails
    plane = [0.0] * 8
    # resting on a reached limit in every failing world and in one success: not found
    failing = _world_measures({'orientation': within, 'plane': plane},
                              [True, False, False, False, True, True, True, True])
    measures = summarize(failing, ORIENTATION_01)
    assert measures.limit_contact_share == 5 / 8  # the earlier rule would have said found
    assert measures.limit_share_of_successes == 0.25 and not measures.joint_limits_found
    # in half the successes, a quarter of the worlds: found
    found = _world_measures({'orientation': within, 'plane': plane},
                            [True, True, False, False, False, False, False, False])
    measures = summarize(found, ORIENTATION_01)
    assert measures.limit_share_of_successes == LIMITS_FOUND_SHARE
    assert measures.limit_success_share == LIMITS_FOUND_MIN_SHARE
    assert measures.joint_limits_found
    # every success on a limit, but too few successes: not found
    rare = _world_measures({'orientation': [0.05] + [0.5] * 7, 'plane': [0.0] * 8},
                           [True] + [False] * 7)
    assert not summarize(rare, ORIENTATION_01).joint_limits_found


class FinalJoints:
    """Records each world's last frame: angles, limits, initial angles, touching links."""

    def __init__(self):
        self.last = {}
        self.world = 0

    def on_world(self, index, simulator):
        self.world = index

    def on_frame(self, step, simulator):
        client, hand, links = simulator.client, simulator.hand, simulator.model.links
        angles = [state[0] for state in client.getJointStates(hand, list(range(len(links))))]
        touching = {point[3] for point in client.getContactPoints(hand, simulator.object_body)
                    if point[8] <= 0.001}
        self.last[self.world] = (angles, links, touching)


def _reached(angle, link):
    """Return the rule written out again: on a limit that the initial angle was not on."""
    lower, upper, start = link.lower_limit, link.upper_limit, link.initial_angle
    on_lower = angle <= lower + LIMIT_TOLERANCE and start > lower + LIMIT_TOLERANCE
    on_upper = angle >= upper - LIMIT_TOLERANCE and start < upper - LIMIT_TOLERANCE
    return on_lower or on_upper


def _final_kind(x, task, world):
    """Return (looser rule, stricter rule, rule written out, final joints) of one rollout."""
    measured = measure_worlds(x, task, world)
    final = FinalJoints()
    design = _TaskContext.of(task).genome_spec().decode(x)
    evaluation = evaluate_design(design, task, world, on_frame=final.on_frame,
                                 frame_every=task.num_steps, on_world=final.on_world)
    if evaluation.collision:
        return bool(measured.limit_contacts[0]), bool(measured.limit_reached[0]), False, None
    angles, links, touching = final.last[0]
    reached = any(touching.intersection(finger)
                  and any(_reached(angles[j], links[j]) for j in finger)
                  for finger in fingers(links))
    return (bool(measured.limit_contacts[0]), bool(measured.limit_reached[0]), reached,
            (angles, links))


def _started_on_final_limits(x, task, angles, links):
    """Return x with each joint that ended on a limit starting on that limit."""
    spec = genome_spec(task)
    physical = dict(zip(spec.names, spec.to_physical(x)))
    for name, angle, link in zip(_joint_names(spec), angles, links):
        for limit in (link.lower_limit, link.upper_limit):
            if abs(angle - limit) <= LIMIT_TOLERANCE:
                physical[name + '.initial_angle'] = limit
    return spec.encode(physical)


def _joint_names(spec):
    return [name[:-len('.initial_angle')] for name in spec.names
            if name.endswith('.initial_angle')]


def test_a_joint_that_starts_on_its_limit_has_not_reached_it():
    task = load_task(TASK5).replace(seed=1)
    spec = genome_spec(task)
    world = unseen_world_states(task, 1)
    generator = np.random.default_rng(3)
    kinds = set()
    for _ in range(24):
        x = generator.random(len(spec.names))
        looser, stricter, written_out, final = _final_kind(x, task, world)
        assert stricter == written_out
        kinds.add((looser, stricter))
        if looser and stricter:
            # the same design with its resting joints starting on the limits they ended on
            looser, stricter, written_out, _ = _final_kind(
                _started_on_final_limits(x, task, *final), task, world)
            assert stricter == written_out
            kinds.add((looser, stricter))
        if {(True, True), (True, False)} <= kinds:
            break
    # a design resting on a limit it reached counts; resting on one it started on (which
    # the earlier rule counted) does not
    assert {(True, True), (True, False)} <= kinds, kinds


def test_old_records_without_the_reached_limits_are_measured_again(tmp_path):
    errors = {'plane': [0.001], 'orientation': [0.2]}
    record = {'worlds': {'errors': errors, 'initial_errors': errors, 'collisions': [False],
                         'limit_contacts': [True]}}
    path = tmp_path / 'run.json'
    path.write_text(json.dumps(record))
    assert folders.read_measures(path, ('plane',)) is None
    record['worlds']['limit_reached'] = [True]
    path.write_text(json.dumps(record))
    assert folders.read_measures(path, ('plane', 'pose')) == record
    measures = campaign_measures.world_measures_of(record['worlds'])
    assert dataclasses.is_dataclass(measures) and measures.errors['pose'][0] == 2.0


@pytest.mark.parametrize('engine', ['pybullet', 'mujoco'])
def test_what_the_hand_did_tells_a_hand_that_never_reaches_the_box_from_one_that_holds_it(
        engine):
    # Task 4's two fingers of one joint beside the box: hanging still, they never touch it;
    # swung towards it about the vertical plane's axis, they turn it and hold it between them
    task = load_task(ROOT / 'config' / 'reproduce' / 'task4_structure.yaml').replace(
        structure=(1, 1), seed=2)
    task = task.replace(physics=task.physics.with_engines((engine,)))
    spec = genome_spec(task)
    worlds = unseen_world_states(task, 4)

    def hand(torque):
        fingers = tuple(FingerDesign((side * 0.04, side * 0.015), (0.065,),
                                     (JointDesign(math.pi / 2, 0.0, -0.4, 0.4),))
                        for side in (-1, 1))
        return spec.encode(Design(HandDesign(fingers, 0.6),
                                  ControllerDesign('torque', np.array([[-torque, torque]]))))

    still = measure_worlds(hand(0.0), task, worlds)
    assert not still.touched.any() and not still.touching.any()
    pushing = measure_worlds(hand(0.01), task, worlds)
    assert pushing.touched.all() and pushing.touching.sum() >= 3
    for measures in (still, pushing):
        groups = np.array([worlds for _, worlds in unseen.behaviours(measures)])
        np.testing.assert_array_equal(groups.sum(axis=0), 1)  # each world in one of them
        # the flags pick worlds (a mask, not indices): the behaviours' successes add up
        within = measures.errors['orientation'] < 0.1
        assert groups.dtype == bool and sum(within[worlds].sum() for worlds in groups) == (
            within.sum())
    assert unseen.behaviour_lines(still, POSE)[4].startswith('| never touches the object | 100')
