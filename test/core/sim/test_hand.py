"""The hand model: its URDF and its PyBullet build come from one link table and agree."""

import math
import xml.etree.ElementTree as ElementTree

from hand_codesign.core.design import FingerDesign, HandDesign, JointDesign
from hand_codesign.core.sim.hand import build_hand, hand_model, hand_urdf
from hand_codesign.core.task import HandSpec
import numpy as np
import pybullet
from pybullet_utils.bullet_client import BulletClient
import pytest
import yourdfpy

HAND = HandSpec(base_position=(0.0, 0.0, 0.3),
                base_orientation=(-math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5)),
                palm_size=(0.14, 0.01, 0.06), segment_radius=0.007, segment_density=1000.0)


def two_by_three():
    """Return a 2x3 hand with different axes, limits (one joint unlimited) and angles."""
    fingers = []
    for finger, x in enumerate((-0.04, 0.05)):
        joints = tuple(JointDesign(axis_angle=0.3 * joint + finger, initial_angle=0.1 * joint,
                                   lower_limit=None if (finger, joint) == (1, 2) else -1.0,
                                   upper_limit=None if (finger, joint) == (1, 2) else 1.2)
                       for joint in range(3))
        fingers.append(FingerDesign(position=(x, 0.01 * finger),
                                    segment_lengths=(0.05, 0.04, 0.03), joints=joints))
    return HandDesign(fingers=tuple(fingers), friction=0.7)


@pytest.fixture
def client():
    connection = BulletClient(connection_mode=pybullet.DIRECT)
    yield connection
    connection.disconnect()


def test_urdf_parses_with_the_design_joints(tmp_path):
    design = two_by_three()
    assert ElementTree.fromstring(hand_urdf(design, HAND)).get('name') == 'hand'
    text = hand_urdf(design, HAND, capsules=False)  # URDF specification shapes only
    path = tmp_path / 'hand.urdf'
    path.write_text(text)
    robot = yourdfpy.URDF.load(str(path), load_meshes=False, build_scene_graph=False)
    joints = [robot.joint_map[name] for name in robot.actuated_joint_names]
    assert len(joints) == design.num_joints == 6
    flat = [joint for finger in design.fingers for joint in finger.joints]
    for joint, spec in zip(joints, flat):
        expected_axis = (math.cos(spec.axis_angle), 0.0, math.sin(spec.axis_angle))
        np.testing.assert_allclose(joint.axis, expected_axis, atol=1e-12)
        if spec.lower_limit is None:
            assert joint.type == 'continuous'
        else:
            assert joint.type == 'revolute'
            assert (joint.limit.lower, joint.limit.upper) == (spec.lower_limit,
                                                              spec.upper_limit)
    # the first joint of each finger sits on the palm surface at the finger's (x, z)
    first = robot.joint_map['finger1_segment0_joint']
    np.testing.assert_allclose(first.origin[:3, 3], (0.05, 0.005, 0.01))
    second = robot.joint_map['finger1_segment1_joint']
    np.testing.assert_allclose(second.origin[:3, 3], (0.0, 0.05, 0.0))
    segment = robot.link_map['finger0_segment0']
    assert [c.geometry.sphere is not None for c in segment.collisions] == [False, True, True]
    assert segment.inertial.mass == pytest.approx(1000.0 * math.pi * 0.007 ** 2 * 0.05)


@pytest.mark.parametrize('name', ['hand', 'a & b <c>', 'say "hi"', 'it\'s "x"', 'tab\tline\n'])
def test_a_robot_name_reads_back_as_written(name):
    assert ElementTree.fromstring(hand_urdf(two_by_three(), HAND, name)).get('name') == name


def test_urdf_and_direct_build_give_the_same_hand(client, tmp_path):
    design = two_by_three()
    model = hand_model(design, HAND)
    built = build_hand(client, model, HAND.base_position, HAND.base_orientation)
    path = tmp_path / 'hand.urdf'
    path.write_text(hand_urdf(design, HAND))
    loaded = client.loadURDF(str(path), HAND.base_position, HAND.base_orientation,
                             useFixedBase=True,
                             flags=(client.URDF_USE_SELF_COLLISION
                                    | client.URDF_USE_INERTIA_FROM_FILE))
    assert client.getNumJoints(built) == client.getNumJoints(loaded) == 6
    for index, link in enumerate(model.links):
        client.resetJointState(loaded, index, link.initial_angle)
        info = client.getJointInfo(loaded, index)
        assert info[2] == client.JOINT_REVOLUTE
        np.testing.assert_allclose(info[13], link.joint_axis, atol=1e-12)
        built_dynamics = client.getDynamicsInfo(built, index)
        loaded_dynamics = client.getDynamicsInfo(loaded, index)
        assert built_dynamics[0] == pytest.approx(loaded_dynamics[0])  # mass
        assert built_dynamics[1] == pytest.approx(0.7)  # friction
        np.testing.assert_allclose(built_dynamics[2], loaded_dynamics[2], rtol=1e-9)
    # the loaded URDF has the limits of the design; unlimited means lower > upper in PyBullet
    assert client.getJointInfo(loaded, 0)[8:10] == (-1.0, 1.2)
    assert client.getJointInfo(loaded, 5)[8] > client.getJointInfo(loaded, 5)[9]
    probe = client.createCollisionShape(client.GEOM_SPHERE, radius=0.001)
    for angles in ([link.initial_angle for link in model.links], [0.5, -0.3, 0.9, 0.2, 1.0, -2]):
        for index, angle in enumerate(angles):
            client.resetJointState(built, index, angle)
            client.resetJointState(loaded, index, angle)
        for index in range(6):
            built_state = client.getLinkState(built, index, computeForwardKinematics=True)
            loaded_state = client.getLinkState(loaded, index, computeForwardKinematics=True)
            np.testing.assert_allclose(built_state[4], loaded_state[4], atol=1e-9)
            np.testing.assert_allclose(built_state[0], loaded_state[0], atol=1e-9)
            # same collision geometry: the same distances to probe points around the link
            for offset in ((0.02, 0.0, 0.0), (0.0, 0.0, -0.03), (0.0, 0.015, 0.01)):
                point = np.add(built_state[4], offset)
                distances = [client.getClosestPoints(
                    body, -1, 1.0, linkIndexA=index, collisionShapeB=probe,
                    collisionShapePositionB=point)[0][8] for body in (built, loaded)]
                assert distances[0] == pytest.approx(distances[1], abs=1e-9)


def test_build_starts_at_the_initial_angles_with_free_joints(client):
    design = two_by_three()
    model = hand_model(design, HAND)
    body = build_hand(client, model, HAND.base_position, HAND.base_orientation)
    angles = [state[0] for state in client.getJointStates(body, list(range(6)))]
    assert angles == pytest.approx([0.0, 0.1, 0.2, 0.0, 0.1, 0.2])
    # the palm normal (+y of the hand) points down: the fingers hang below the palm
    tip = client.getLinkState(body, 2, computeForwardKinematics=True)[4]
    assert tip[2] < HAND.base_position[2]


def test_segment_geometry_stays_between_its_joints():
    short = JointDesign(axis_angle=0.0, initial_angle=0.0)
    design = HandDesign(fingers=(FingerDesign(position=(0.0, 0.0), segment_lengths=(0.05, 0.004),
                                              joints=(short, short)),), friction=0.5)
    long_link, short_link = hand_model(design, HAND).links
    assert long_link.radius == 0.007
    assert long_link.cylinder_height == pytest.approx(0.05 - 0.014)
    assert short_link.radius == pytest.approx(0.002)  # half its length
    assert short_link.cylinder_height == 0.0
    assert long_link.mass == pytest.approx(1000.0 * math.pi * 0.007 ** 2 * 0.05)


def test_a_bad_design_is_refused_with_its_finger():
    joint = JointDesign(axis_angle=0.0, initial_angle=0.0)
    design = HandDesign(fingers=(FingerDesign(position=(0.0, 0.0), segment_lengths=(0.0,),
                                              joints=(joint,)),), friction=0.5)
    with pytest.raises(ValueError, match='finger 0 segment 0'):
        hand_model(design, HAND)
