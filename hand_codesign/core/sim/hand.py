"""
The hand model: one link table, rendered as a URDF string or built in PyBullet.

`hand_model(design)` turns a HandDesign into a HandModel, a table of links and joints in SI
units. That table is the single source of truth: `hand_urdf` writes it as URDF text and
`build_hand` creates the very same multibody in a PyBullet client with `createMultiBody`
(building from the table directly is several times faster than writing and parsing URDF;
test_hand.py checks that both give identical link frames, limits and collision boxes).

Geometry (hand frame of hand_codesign.core.design): the palm is a box centred on the base
with its normal along +y. A finger's first joint sits on the palm surface at (x, palm
thickness / 2, z). Every segment is a link whose frame is at its joint; it extends along its
own +y by its length, where the next joint sits. Its collision shape is a capsule lying
entirely between the two joints: radius min(segment_radius, length / 2), cylinder height
length - 2 radius, so segments of one finger touch only at the joints and a finger starts on
the palm surface instead of inside it. Each joint's axis is (cos a, 0, sin a) in the frame of
the link before it. Inertia is that of a solid cylinder of the segment's length.
"""

from dataclasses import dataclass
import math
from typing import Optional, Tuple
from xml.sax.saxutils import quoteattr

from hand_codesign.core.design import HandDesign
from hand_codesign.core.rotations import axis_angle_quaternion, quaternion_multiply
from hand_codesign.core.task import HandSpec

# Rotates a capsule's own axis (z in Bullet and URDF) onto the segment's +y.
_CAPSULE_ORIENTATION = (-math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5))
_CAPSULE_RPY = (-math.pi / 2, 0.0, 0.0)


# The root link of the URDF: the palm, fixed to the world at the task's hand base pose.
PALM_LINK = 'palm'
# The URDF effort limit; the simulated torques are whatever the policy asks for.
MAX_JOINT_FORCE = 1000.0


@dataclass(frozen=True)
class LinkSpec:
    """One finger segment and the hinge joint before it, in the parent link's frame."""

    name: str
    joint_name: str
    parent: int  # index of the parent link in HandModel.links, -1 for the palm
    joint_position: Tuple[float, float, float]
    joint_axis: Tuple[float, float, float]
    lower_limit: Optional[float]
    upper_limit: Optional[float]
    initial_angle: float
    length: float
    radius: float
    cylinder_height: float
    mass: float
    inertia: Tuple[float, float, float]  # diagonal, about the centre of mass, link axes

    @property
    def centre(self):
        """Return the segment's centre of mass in its own link frame."""
        return (0.0, self.length / 2, 0.0)


@dataclass(frozen=True)
class HandModel:
    """The link table of a hand: palm box and segments, finger by finger, base to tip."""

    palm_size: Tuple[float, float, float]
    palm_mass: float
    friction: float
    links: Tuple[LinkSpec, ...]
    max_joint_force: float
    # the palm's pose in the world: position (m) and orientation (x, y, z, w); palm_pose
    base_position: Tuple[float, float, float] = (0.0, 0.0, 0.0)
    base_orientation: Tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)

    @property
    def num_joints(self):
        return len(self.links)

    @property
    def initial_angles(self):
        """Return the initial joint angles, in joint order."""
        return tuple(link.initial_angle for link in self.links)


def _segment_link(name, parent, joint_position, joint, length, hand_spec):
    radius = min(hand_spec.segment_radius, length / 2)
    mass = hand_spec.segment_density * math.pi * radius ** 2 * length
    across = mass * (3 * radius ** 2 + length ** 2) / 12
    along = mass * radius ** 2 / 2
    lower, upper = joint.lower_limit, joint.upper_limit
    if lower is None or upper is None:
        lower = upper = None
    return LinkSpec(
        name=name, joint_name=name + '_joint', parent=parent,
        joint_position=tuple(float(v) for v in joint_position),
        joint_axis=(math.cos(joint.axis_angle), 0.0, math.sin(joint.axis_angle)),
        lower_limit=None if lower is None else float(lower),
        upper_limit=None if upper is None else float(upper),
        initial_angle=float(joint.initial_angle), length=float(length), radius=radius,
        cylinder_height=max(float(length) - 2 * radius, 0.0), mass=mass,
        inertia=(across, along, across))


def palm_pose(design: HandDesign, hand_spec: HandSpec):
    """
    Return (position, orientation x, y, z, w) of the palm in the world: where the hand stands.

    The task's base_position and base_orientation, unless the design places the palm (a
    searched placement, core.task.genome): its base_position, and its base_yaw as a turn
    about the world vertical through the palm centre after the task's orientation. A yaw of
    0 leaves the task's orientation exactly as it is.
    """
    position = (hand_spec.base_position if design.base_position is None
                else design.base_position)
    yaw = hand_spec.base_yaw if design.base_yaw is None else design.base_yaw
    orientation = tuple(hand_spec.base_orientation)
    if yaw != 0.0:
        orientation = quaternion_multiply(axis_angle_quaternion((0.0, 0.0, 1.0), yaw),
                                          orientation)
    return (tuple(float(v) for v in position), tuple(float(v) for v in orientation))


def hand_model(design: HandDesign, hand_spec: HandSpec):
    """Return the HandModel (link table) of a hand design with the task's fixed sizes."""
    links = []
    surface = hand_spec.palm_size[1] / 2
    for finger_index, finger in enumerate(design.fingers):
        if len(finger.segment_lengths) != len(finger.joints):
            raise ValueError(
                f'finger {finger_index}: {len(finger.segment_lengths)} segment lengths for '
                f'{len(finger.joints)} joints; expected one length per joint')
        parent = -1
        joint_position = (finger.position[0], surface, finger.position[1])
        for joint_index, (joint, length) in enumerate(zip(finger.joints,
                                                          finger.segment_lengths)):
            if not length > 0:
                raise ValueError(
                    f'finger {finger_index} segment {joint_index}: length {length!r}; '
                    'expected a positive length in metres')
            name = f'finger{finger_index}_segment{joint_index}'
            links.append(_segment_link(name, parent, joint_position, joint, length,
                                       hand_spec))
            parent = len(links) - 1
            joint_position = (0.0, length, 0.0)
    position, orientation = palm_pose(design, hand_spec)
    return HandModel(palm_size=tuple(float(v) for v in hand_spec.palm_size),
                     palm_mass=float(hand_spec.palm_mass), friction=float(design.friction),
                     links=tuple(links), max_joint_force=MAX_JOINT_FORCE,
                     base_position=position, base_orientation=orientation)


def _vector(values):
    return ' '.join(repr(float(v)) for v in values)


def _inertial_xml(mass, centre, inertia):
    ixx, iyy, izz = inertia
    return (f'    <inertial>\n      <origin xyz="{_vector(centre)}" rpy="0 0 0"/>\n'
            f'      <mass value="{mass!r}"/>\n'
            f'      <inertia ixx="{ixx!r}" ixy="0" ixz="0" iyy="{iyy!r}" iyz="0" '
            f'izz="{izz!r}"/>\n    </inertial>\n')


def _contact_xml(friction):
    return f'    <contact>\n      <lateral_friction value="{friction!r}"/>\n    </contact>\n'


def _palm_xml(model):
    sx, sy, sz = model.palm_size
    inertia = (model.palm_mass * (sy ** 2 + sz ** 2) / 12,
               model.palm_mass * (sx ** 2 + sz ** 2) / 12,
               model.palm_mass * (sx ** 2 + sy ** 2) / 12)
    geometry = f'<box size="{_vector(model.palm_size)}"/>'
    return (f'  <link name={quoteattr(PALM_LINK)}>\n' + _contact_xml(model.friction)
            + _inertial_xml(model.palm_mass, (0, 0, 0), inertia)
            + f'    <visual>\n      <geometry>{geometry}</geometry>\n    </visual>\n'
            + f'    <collision>\n      <geometry>{geometry}</geometry>\n    </collision>\n'
            + '  </link>\n')


def _capsule_xml(link, element, capsules):
    """Return the capsule of a segment as <visual> or <collision> element(s)."""
    origin = f'<origin xyz="{_vector(link.centre)}" rpy="{_vector(_CAPSULE_RPY)}"/>'
    if capsules:
        geometry = f'<capsule radius="{link.radius!r}" length="{link.cylinder_height!r}"/>'
        return (f'    <{element}>\n      {origin}\n      <geometry>{geometry}</geometry>\n'
                f'    </{element}>\n')
    # The same solid from the shapes of the URDF specification: a cylinder and two spheres.
    parts = [f'    <{element}>\n      {origin}\n      <geometry><cylinder '
             f'radius="{link.radius!r}" length="{link.cylinder_height!r}"/></geometry>\n'
             f'    </{element}>\n'] if link.cylinder_height > 0 else []
    for end in (link.radius, link.length - link.radius):
        parts.append(f'    <{element}>\n      <origin xyz="{_vector((0.0, end, 0.0))}" '
                     f'rpy="0 0 0"/>\n      <geometry><sphere radius="{link.radius!r}"/>'
                     f'</geometry>\n    </{element}>\n')
    return ''.join(parts)


def _segment_xml(model, link, capsules):
    parent = PALM_LINK if link.parent < 0 else model.links[link.parent].name
    if link.lower_limit is None:
        joint_type, limit = 'continuous', ''
    else:
        joint_type = 'revolute'
        limit = f' lower="{link.lower_limit!r}" upper="{link.upper_limit!r}"'
    return (f'  <link name={quoteattr(link.name)}>\n' + _contact_xml(model.friction)
            + _inertial_xml(link.mass, link.centre, link.inertia)
            + _capsule_xml(link, 'visual', capsules)
            + _capsule_xml(link, 'collision', capsules) + '  </link>\n'
            + f'  <joint name={quoteattr(link.joint_name)} type="{joint_type}">\n'
            + f'    <parent link={quoteattr(parent)}/>\n'
            + f'    <child link={quoteattr(link.name)}/>\n'
            + f'    <origin xyz="{_vector(link.joint_position)}" rpy="0 0 0"/>\n'
            + f'    <axis xyz="{_vector(link.joint_axis)}"/>\n'
            + f'    <limit effort="{model.max_joint_force!r}" velocity="100.0"{limit}/>\n'
            + '  </joint>\n')


def model_urdf(model: HandModel, name='hand', capsules=True):
    """
    Return the URDF text of a hand model (initial angles are not part of URDF).

    capsules=True writes the segments as <capsule> elements, which PyBullet reads (the
    simulated hand); capsules=False writes each as a cylinder between two spheres, the same
    solid in the shapes of the URDF specification, for parsers that know only those.
    """
    parts = ['<?xml version="1.0"?>\n', f'<robot name={quoteattr(name)}>\n', _palm_xml(model)]
    parts.extend(_segment_xml(model, link, capsules) for link in model.links)
    parts.append('</robot>\n')
    return ''.join(parts)


def hand_urdf(design: HandDesign, hand_spec: HandSpec, name='hand', capsules=True):
    """Return the URDF text of a hand design with the task's fixed sizes (task.hand)."""
    return model_urdf(hand_model(design, hand_spec), name, capsules)


def build_hand(client, model: HandModel, base_position=(0.0, 0.0, 0.0),
               base_orientation=(0.0, 0.0, 0.0, 1.0)):
    """
    Create the hand in a PyBullet client and return its body id.

    The palm is the fixed base. Self-collision is on between non-adjacent links, joints start
    at their initial angles, and the default velocity motors are switched off so that joint
    torques alone drive the hand.
    """
    half_palm = [v / 2 for v in model.palm_size]
    palm_shape = client.createCollisionShape(client.GEOM_BOX, halfExtents=half_palm)
    shapes, positions, parents, axes, masses, centres = [], [], [], [], [], []
    for link in model.links:
        shapes.append(client.createCollisionShape(
            client.GEOM_CAPSULE, radius=link.radius, height=link.cylinder_height,
            collisionFramePosition=link.centre,
            collisionFrameOrientation=_CAPSULE_ORIENTATION))
        positions.append(link.joint_position)
        parents.append(link.parent + 1)  # createMultiBody counts the base as 0
        axes.append(link.joint_axis)
        masses.append(link.mass)
        centres.append(link.centre)
    count = len(model.links)
    identity = [(0.0, 0.0, 0.0, 1.0)] * count
    body = client.createMultiBody(
        baseMass=0.0, baseCollisionShapeIndex=palm_shape, basePosition=base_position,
        baseOrientation=base_orientation, linkMasses=masses, linkCollisionShapeIndices=shapes,
        linkVisualShapeIndices=[-1] * count, linkPositions=positions,
        linkOrientations=identity, linkInertialFramePositions=centres,
        linkInertialFrameOrientations=identity, linkParentIndices=parents,
        linkJointTypes=[client.JOINT_REVOLUTE] * count, linkJointAxis=axes,
        flags=client.URDF_USE_SELF_COLLISION)
    configure_hand(client, body, model)
    return body


def configure_hand(client, body, model: HandModel):
    """Set friction, inertia, limits, initial angles and free motors of a built hand."""
    client.changeDynamics(body, -1, lateralFriction=model.friction)
    for index, link in enumerate(model.links):
        arguments = {'lateralFriction': model.friction, 'localInertiaDiagonal': link.inertia}
        if link.lower_limit is not None:
            arguments.update(jointLowerLimit=link.lower_limit,
                             jointUpperLimit=link.upper_limit)
        client.changeDynamics(body, index, **arguments)
        client.resetJointState(body, index, link.initial_angle)
    indices = list(range(len(model.links)))
    client.setJointMotorControlArray(body, indices, client.VELOCITY_CONTROL,
                                     forces=[0.0] * len(indices))
