"""
A decoded candidate in physical units: the hand's morphology and its controller.

The genome (hand_codesign.core.task.genome) decodes into a Design; the simulator builds a Design,
the URDF export writes one, and a seeded search starts from one. All values are SI: metres,
radians, kilograms, newton metres.

Hand frame: the palm is a thin box centred on the hand's base; its normal is the +y axis of
the hand frame. Each finger is attached at (x, z) on the palm and extends along +y as a chain
of capsule segments, each segment preceded by a hinge joint. A joint's axis lies in the plane
perpendicular to the finger: axis angle a gives the axis (cos a, 0, sin a) in the frame of the
segment before it, so different axes within a finger give the dexterity of multi-DoF joints.
"""

from dataclasses import dataclass
from typing import Optional, Tuple

import numpy as np


@dataclass(frozen=True)
class JointDesign:
    """One hinge joint: axis angle, limits and initial angle (radians)."""

    axis_angle: float
    initial_angle: float
    lower_limit: Optional[float] = None  # None: the joint has no limit
    upper_limit: Optional[float] = None


@dataclass(frozen=True)
class FingerDesign:
    """A finger: where it sits on the palm and its chain of joint + segment pairs."""

    position: Tuple[float, float]  # (x, z) on the palm in the hand frame, metres
    segment_lengths: Tuple[float, ...]  # one per joint, metres
    joints: Tuple[JointDesign, ...]


@dataclass(frozen=True)
class HandDesign:
    """The morphology: fingers on a palm and one friction coefficient for the whole hand."""

    fingers: Tuple[FingerDesign, ...]
    friction: float
    # where the palm stands when the search places it (beyond the paper): the palm centre in
    # the world frame (m) and a turn about the world vertical after the task's orientation
    # (rad); None: the task's fixed base_position and base_yaw
    base_position: Optional[Tuple[float, float, float]] = None
    base_yaw: Optional[float] = None

    @property
    def structure(self):
        """Return the joints per finger, e.g. (2, 2)."""
        return tuple(len(finger.joints) for finger in self.fingers)

    @property
    def num_joints(self):
        return sum(self.structure)


@dataclass(frozen=True)
class ControllerDesign:
    """
    The control policy's parameters, joints ordered finger by finger, base to tip.

    kind 'torque': `values` holds joint torques, one row per knot (K x joints); the task's
    policy says whether they are held constant over intervals or interpolated.
    kind 'pd': `values` holds target joint angles, one row per keyframe, tracked with the
    feed-forward PD law of equation (1) with gains `kp` and `kd` (one per joint).
    """

    kind: str
    values: np.ndarray
    kp: Optional[np.ndarray] = None
    kd: Optional[np.ndarray] = None

    def _identity(self):
        def as_tuple(array):
            return None if array is None else (np.shape(array),
                                               tuple(np.ravel(array).tolist()))
        return (self.kind, as_tuple(self.values), as_tuple(self.kp), as_tuple(self.kd))

    def __eq__(self, other):
        # compare the arrays by value (the generated __eq__ fails on numpy arrays)
        if not isinstance(other, ControllerDesign):
            return NotImplemented
        return self._identity() == other._identity()

    def __hash__(self):
        return hash(self._identity())


@dataclass(frozen=True)
class Design:
    """A whole candidate: hand and controller."""

    hand: HandDesign
    controller: ControllerDesign
