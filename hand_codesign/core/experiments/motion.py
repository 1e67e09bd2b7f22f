"""
A design's motion: one world's rollout re-simulated, frame by frame, for viewers.

`rollout_motion(design, task, world)` evaluates a Design on one world state with
core.evaluate (the evaluators' code path) and keeps, at FRAMES_PER_SECOND frames per simulated
second from step 0, the joint angles, the link frames and the object's pose. A design that
starts in collision is not simulated: its Motion holds one frame, the hand at its initial
angles and the object at its start.

`design_urdf(task, design, name)` is the hand as the URDF that `hand-codesign export` writes
and a robot model shows (core.sim.hand.hand_urdf, segments as cylinders between spheres), so
a viewer's robot_description and an exported hand.urdf are one text. Together with
core.sim.geometry.joint_transforms at a frame's angles, a Motion is what a robot state
publisher would give: the palm fixed at `palm` in the world and each joint's transform.
"""

from dataclasses import dataclass
from typing import Tuple

from hand_codesign.core.evaluate import evaluate_design
from hand_codesign.core.evaluate import new_simulator
from hand_codesign.core.sim.geometry import link_frames
from hand_codesign.core.sim.hand import hand_model
from hand_codesign.core.sim.hand import hand_urdf
from hand_codesign.core.sim.hand import HandModel
from hand_codesign.core.sim.worlds import object_state

FRAMES_PER_SECOND = 25


@dataclass(frozen=True)
class Motion:
    """
    One world's rollout of a design, frame by frame.

    times: (frames,) s from the start; joint_angles: (frames, joints) rad in joint order;
    link_poses: per frame, every link frame's world (position, quaternion xyzw); object_poses:
    per frame, the object's world pose; palm: the palm's fixed world pose.
    """

    model: HandModel
    palm: Tuple
    times: Tuple[float, ...]
    joint_angles: Tuple[Tuple[float, ...], ...]
    link_poses: Tuple
    object_poses: Tuple
    simulated: bool  # False: the design starts in collision, one frame shows its start


def frame_every(task, frames_per_second=FRAMES_PER_SECOND):
    """Return the physics steps between two frames at `frames_per_second`."""
    return max(1, int(round(1.0 / (frames_per_second * task.time_step))))


def rollout_motion(design, task, world, frames_per_second=FRAMES_PER_SECOND):
    """Return the Motion of a Design on `task` in one WorldState (core.sim.worlds)."""
    model = hand_model(design.hand, task.hand)
    palm = (tuple(model.base_position), tuple(model.base_orientation))  # searched or fixed
    frames = []

    def grab(step, simulator):
        position, orientation = simulator.object_pose()
        frames.append((step * task.time_step, tuple(float(a) for a in simulator.joint_angles()),
                       tuple(simulator.link_poses()), (tuple(position), tuple(orientation))))

    with new_simulator(task.physics.engine) as simulator:
        evaluate_design(design, task, worlds=[world], simulator=simulator, on_frame=grab,
                        frame_every=frame_every(task, frames_per_second))
    simulated = bool(frames)
    if not simulated:
        state = object_state(task, world)
        frames.append((0.0, model.initial_angles, tuple(link_frames(model, palm)),
                       (tuple(state.position), tuple(state.orientation))))
    times, angles, links, objects = zip(*frames)
    return Motion(model, palm, times, angles, links, objects, simulated)


def design_urdf(task, design, name):
    """Return the URDF text of a Design's hand (as `hand-codesign export` writes hand.urdf)."""
    return hand_urdf(design.hand, task.hand, name=name, capsules=False)


__all__ = ['design_urdf', 'FRAMES_PER_SECOND', 'frame_every', 'Motion', 'rollout_motion']
