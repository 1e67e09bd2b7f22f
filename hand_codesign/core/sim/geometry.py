"""
What a hand and its task look like, as plain shapes in the world frame: for 3D viewers.

A viewer (Foxglove, Lichtblick, RViz) draws primitive shapes; this module turns the core's
hand model (core.sim.hand.HandModel, the same table the simulator builds) and the task's object
and goals into such shapes, without ROS: `ros.conversions` makes them
visualization_msgs/Marker messages.

- the palm: a box at the hand's base;
- each finger segment: the capsule of the simulated hand drawn as a cylinder between two
  spheres (a Marker has no capsule), placed from its link frame;
- each joint's axis: an arrow from the joint along the axis;
- the object: its shape at its start pose (the nominal world), and a translucent copy at every
  goal pose (a goal without a position keeps the start position, one without an orientation
  keeps the start orientation).

Link frames come either from forward kinematics at the initial joint angles (`link_frames`,
the hand as designed, before any motion) or from a simulation (replay), so a rollout is drawn
with the very shapes of the design. `joint_transforms` gives each joint's transform (parent
link to child link) at some joint angles: the /tf of the hand as a robot model. Poses are
(position xyz, quaternion xyzw), sizes are the full extents along the shape's own axes (a
cylinder's axis is its z).
"""

from dataclasses import dataclass
import math
from typing import Tuple

from hand_codesign.core.rotations import axis_angle_quaternion, compose, rotate
from hand_codesign.core.sim.hand import hand_model
from hand_codesign.core.sim.hand import PALM_LINK
from hand_codesign.core.sim.objectives import goal_schedule
from hand_codesign.core.sim.worlds import object_state
from hand_codesign.core.sim.worlds import WorldState

PALM_COLOUR = (0.55, 0.55, 0.6, 1.0)
SEGMENT_COLOUR = (0.85, 0.55, 0.25, 1.0)
AXIS_COLOUR = (0.9, 0.15, 0.15, 1.0)
OBJECT_COLOUR = (0.2, 0.45, 0.85, 1.0)
GOAL_COLOUR = (0.2, 0.8, 0.3, 0.35)
AXIS_LENGTH_FACTOR = 1.5  # an arrow is this many segment diameters long
IDENTITY = (0.0, 0.0, 0.0, 1.0)
# Turns a shape's own z axis onto a segment's +y: -90 degrees about x.
_Z_TO_Y = (-math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5))


@dataclass(frozen=True)
class Shape:
    """
    One primitive shape in the world frame.

    kind: 'box' | 'sphere' | 'cylinder' | 'arrow'; group: what it belongs to ('palm',
    'segments', 'joint_axes', 'object', 'goals'), a viewer's namespace; for an arrow, `size`
    is (shaft diameter, head diameter, head length) and `points` its start and end.
    """

    kind: str
    group: str
    position: Tuple[float, float, float]
    orientation: Tuple[float, float, float, float]
    size: Tuple[float, float, float]
    colour: Tuple[float, float, float, float]
    points: Tuple[Tuple[float, float, float], ...] = ()


def link_frames(model, base_pose, angles=None):
    """
    Return the world pose of every link frame of a HandModel, in link order.

    base_pose: the palm's (position, orientation); angles: joint angles (default: the initial
    ones). A link's frame sits at its joint; turning the joint turns it about the joint axis.
    """
    frames = []
    for link, (_, _, joint) in zip(model.links, joint_transforms(model, angles)):
        parent = base_pose if link.parent < 0 else frames[link.parent]
        frames.append(compose(parent, joint))
    return frames


def joint_transforms(model, angles=None):
    """
    Return (parent link, child link, (translation, quaternion)) of every joint at `angles`.

    Each is the pose of the child link's frame in its parent's, the joint's origin turned by
    its angle about its axis: what robot_state_publisher computes from the hand's URDF
    (core.sim.hand.model_urdf: link names, origins, axes) and a joint state. Composed from the
    palm's pose down, they give `link_frames`. angles: default the initial ones.
    """
    angles = model.initial_angles if angles is None else angles
    return [(PALM_LINK if link.parent < 0 else model.links[link.parent].name, link.name,
             (tuple(link.joint_position), axis_angle_quaternion(link.joint_axis, float(angle))))
            for link, angle in zip(model.links, angles)]


def hand_shapes(model, base_pose, frames):
    """Return the palm, segment and joint-axis Shapes of a hand whose links are at `frames`."""
    shapes = [Shape('box', 'palm', *_floats_pose(base_pose), tuple(model.palm_size),
                    PALM_COLOUR)]
    for link, frame in zip(model.links, frames):
        diameter = 2 * link.radius
        if link.cylinder_height > 0:
            centre = compose(frame, (link.centre, _Z_TO_Y))
            shapes.append(Shape('cylinder', 'segments', *centre,
                                (diameter, diameter, link.cylinder_height), SEGMENT_COLOUR))
        for end in (link.radius, link.length - link.radius):
            position, _ = compose(frame, ((0.0, end, 0.0), IDENTITY))
            shapes.append(Shape('sphere', 'segments', position, IDENTITY,
                                (diameter,) * 3, SEGMENT_COLOUR))
    for link, frame in zip(model.links, frames):
        # the axis is fixed in the parent's frame, i.e. in the link frame before its turn
        parent = base_pose if link.parent < 0 else frames[link.parent]
        start, _ = compose(parent, (link.joint_position, IDENTITY))
        direction = rotate(parent[1], link.joint_axis)
        length = AXIS_LENGTH_FACTOR * 2 * link.radius
        end = tuple(s + length * d for s, d in zip(start, direction))
        thickness = 0.15 * link.radius
        shapes.append(Shape('arrow', 'joint_axes', start, IDENTITY,
                            (thickness, 2.5 * thickness, 0.3 * length), AXIS_COLOUR,
                            (start, end)))
    return shapes


def object_shapes(shape, size, pose, group='object', colour=OBJECT_COLOUR):
    """Return the Shapes of an object of task shape `shape` and ObjectState size at `pose`."""
    position, orientation = _floats_pose(pose)
    if shape == 'box':
        return [Shape('box', group, position, orientation, tuple(size), colour)]
    if shape == 'sphere':
        return [Shape('sphere', group, position, orientation, (2 * size[0],) * 3, colour)]
    radius, length = size
    diameter = 2 * radius
    shapes = [Shape('cylinder', group, position, orientation, (diameter, diameter, length),
                    colour)]
    for end in (-length / 2, length / 2):
        centre, _ = compose((position, orientation), ((0.0, 0.0, end), IDENTITY))
        shapes.append(Shape('sphere', group, centre, orientation, (diameter,) * 3, colour))
    return shapes


def goal_poses(task, state):
    """Return (time, position, orientation) of every goal of `task` in the world of `state`."""
    schedule = goal_schedule(task)
    times = sorted({goal.time for goal in task.goals.position + task.goals.orientation})
    poses = []
    for time in times:
        position = next((goal.position for goal in task.goals.position if goal.time == time),
                        None)
        orientation = next((goal.orientation for goal in task.goals.orientation
                            if goal.time == time), None)
        position, orientation = schedule.world_goal(position, orientation, state)
        poses.append((float(time),
                      _floats(state.position if position is None else position),
                      _floats(state.orientation if orientation is None else orientation)))
    return poses


def design_shapes(task, design):
    """
    Return the Shapes of a Design on its task: the hand as designed and the object's start.

    The hand stands at its initial joint angles; the object is the task's nominal one at its
    start; a translucent copy of it stands at each goal pose.
    """
    model = hand_model(design.hand, task.hand)
    base = (model.base_position, model.base_orientation)
    state = object_state(task, WorldState.nominal())
    shape = task.object_spec.shape
    shapes = hand_shapes(model, base, link_frames(model, base))
    shapes += object_shapes(shape, state.size, (state.position, state.orientation))
    for _, position, orientation in goal_poses(task, state):
        shapes += object_shapes(shape, state.size, (position, orientation), 'goals',
                                GOAL_COLOUR)
    return shapes


def _floats(values):
    return tuple(float(v) for v in values)


def _floats_pose(pose):
    return _floats(pose[0]), _floats(pose[1])
