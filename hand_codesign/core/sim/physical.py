"""
A candidate's design in physical terms: what a Candidate message carries besides its genome.

An evaluator that is not this package (another language, a person at a test rig) cannot decode
the optimizer's normalized genome; it needs the hand and its controller in SI units. For
every candidate the optimizer sends:

- `design_names` / `design_values`: every morphology value of the hand, fixed ones included
  (the genome holds only the optimized ones), named as the genome names them::

      hand.friction
      finger{i}.position_x, finger{i}.position_z                 hand frame, m
      finger{i}.segment{j}.length                                m
      finger{i}.joint{j}.axis_angle, .initial_angle              rad
      finger{i}.joint{j}.lower_limit, .upper_limit               rad; NaN: no limit
      hand.base_position_x, _y, _z, hand.base_yaw                world, m and rad; only
                                                                 when the search places
                                                                 the palm (beyond the paper)

- `hand_urdf`: the hand as standard URDF (cylinders and spheres, no capsules);
- the controller: its kind ('torque' or 'pd'), mode ('constant' or 'interpolated' torques,
  'pd' for keyframes), whether gravity compensation is added, the knot (or keyframe) times in
  s, the values (knots x joints, N m or rad, joints finger by finger, base to tip) and for PD
  the gains kp and kd per joint.

`design_from_physical` is the inverse: the Design the values describe, bit for bit the one the
genome decodes to, so a simulated rig builds the same hand without the genome.
"""

from dataclasses import dataclass
import math
from typing import Tuple

from hand_codesign.core.design import (ControllerDesign, Design, FingerDesign, HandDesign,
                                       JointDesign)
from hand_codesign.core.sim.hand import hand_urdf
from hand_codesign.core.sim.policies import torque_knot_times
from hand_codesign.core.task.genome import genome_spec
import numpy as np

JOINT_FIELDS = ('axis_angle', 'initial_angle', 'lower_limit', 'upper_limit')


@dataclass(frozen=True)
class PhysicalDesign:
    """The fields of a Candidate that describe its design in SI units (see the module doc)."""

    names: Tuple[str, ...]
    values: Tuple[float, ...]
    urdf: str
    controller_kind: str
    controller_mode: str
    gravity_compensation: bool
    knot_times: Tuple[float, ...]
    controller_values: Tuple[float, ...]  # row-major, knots x joints
    kp: Tuple[float, ...]
    kd: Tuple[float, ...]


PLACEMENT_NAMES = ('hand.base_position_x', 'hand.base_position_y', 'hand.base_position_z',
                   'hand.base_yaw')


def design_names(structure, placed=False):
    """
    Return the names of the morphology values of a hand structure, in message order.

    placed: the design carries its palm's placement (a searched one), named last.
    """
    names = ['hand.friction']
    for finger, joints in enumerate(structure):
        names += [f'finger{finger}.position_x', f'finger{finger}.position_z']
        names += [f'finger{finger}.segment{joint}.length' for joint in range(joints)]
        names += [f'finger{finger}.joint{joint}.{field}' for joint in range(joints)
                  for field in JOINT_FIELDS]
    return tuple(names) + (PLACEMENT_NAMES if placed else ())


def morphology_values(hand):
    """Return the values of a HandDesign in the order of design_names (NaN: no limit)."""
    values = [hand.friction]
    for finger in hand.fingers:
        values += [finger.position[0], finger.position[1]]
        values += list(finger.segment_lengths)
        for joint in finger.joints:
            values += [joint.axis_angle, joint.initial_angle,
                       math.nan if joint.lower_limit is None else joint.lower_limit,
                       math.nan if joint.upper_limit is None else joint.upper_limit]
    if hand.base_position is not None:
        values += [*hand.base_position, hand.base_yaw]
    return tuple(float(value) for value in values)


def knot_times(policy):
    """Return the times (s) of a policy's knots: torque knots or PD keyframes."""
    if policy.kind == 'torque':
        return tuple(torque_knot_times(policy.mode, policy.knots, policy.duration).tolist())
    return tuple(float(time) for time in policy.keyframe_times)


def physical_design(design, task):
    """Return the PhysicalDesign of a Design on `task` (whose hand sizes and policy it uses)."""
    controller = design.controller
    policy = task.policy
    return PhysicalDesign(
        names=design_names(design.hand.structure, design.hand.base_position is not None),
        values=morphology_values(design.hand),
        urdf=hand_urdf(design.hand, task.hand, capsules=False),
        controller_kind=controller.kind,
        controller_mode=policy.mode if policy.kind == 'torque' else 'pd',
        gravity_compensation=bool(policy.gravity_compensation),
        knot_times=knot_times(policy),
        controller_values=tuple(np.asarray(controller.values, dtype=float).ravel().tolist()),
        kp=() if controller.kp is None else tuple(np.asarray(controller.kp).tolist()),
        kd=() if controller.kd is None else tuple(np.asarray(controller.kd).tolist()))


def candidate_design(task, x):
    """Return the PhysicalDesign of normalized genome x on `task`."""
    return physical_design(genome_spec(task).decode(np.asarray(x, dtype=float)), task)


def _limit(value):
    return None if math.isnan(value) else float(value)


def design_from_physical(structure, names, values, controller_kind, controller_values,
                         kp=(), kd=()):
    """
    Return the Design that a Candidate's physical fields describe; ValueError if they do not.

    structure: joints per finger; names/values: design_names/design_values; the controller's
    values row-major, knots x joints.
    """
    structure = tuple(int(joints) for joints in structure)
    expected = design_names(structure, PLACEMENT_NAMES[-1] in tuple(names))
    if tuple(names) != expected:
        raise ValueError(f'design_names do not describe structure {list(structure)}: expected '
                         f'{len(expected)} names starting {list(expected[:3])}, got '
                         f'{len(names)} starting {list(names)[:3]}')
    if len(values) != len(expected):
        raise ValueError(f'{len(values)} design_values for {len(expected)} design_names')
    value = dict(zip(names, (float(v) for v in values)))
    fingers = []
    for finger, joints in enumerate(structure):
        prefix = f'finger{finger}.'
        fingers.append(FingerDesign(
            position=(value[prefix + 'position_x'], value[prefix + 'position_z']),
            segment_lengths=tuple(value[f'{prefix}segment{joint}.length']
                                  for joint in range(joints)),
            joints=tuple(JointDesign(
                axis_angle=value[f'{prefix}joint{joint}.axis_angle'],
                initial_angle=value[f'{prefix}joint{joint}.initial_angle'],
                lower_limit=_limit(value[f'{prefix}joint{joint}.lower_limit']),
                upper_limit=_limit(value[f'{prefix}joint{joint}.upper_limit']))
                for joint in range(joints))))
    joints = sum(structure)
    table = np.asarray(controller_values, dtype=float)
    if joints == 0 or table.size % joints:
        raise ValueError(f'{table.size} controller values for {joints} joints; expected a '
                         'multiple (knots x joints)')
    gains = [None if not len(gain) else np.asarray(gain, dtype=float) for gain in (kp, kd)]
    placed = {}
    if PLACEMENT_NAMES[-1] in value:
        placed = {'base_position': tuple(value[name] for name in PLACEMENT_NAMES[:3]),
                  'base_yaw': value[PLACEMENT_NAMES[-1]]}
    return Design(hand=HandDesign(fingers=tuple(fingers), friction=value['hand.friction'],
                                  **placed),
                  controller=ControllerDesign(kind=controller_kind,
                                              values=table.reshape(-1, joints),
                                              kp=gains[0], kd=gains[1]))
