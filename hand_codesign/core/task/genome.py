"""
The genome: named, bounded values the optimizer searches, and their mapping to a Design.

`genome_spec(task)` lists every optimized value of the task's hand structure and policy, each
with a name and physical bounds from the task (Table I), and fixes all other values of the
Design. Genes are ordered morphology first, then controller:

    hand.friction
    hand.base_position_{x,y,z}, hand.base_yaw              world frame, m and rad (searched
                                                           palm placement, beyond the paper)
    finger{i}.position_x, finger{i}.position_z             hand frame, m
    finger{i}.segment{j}.length                            m
    finger{i}.joint{j}.initial_angle, .axis_angle          rad
    finger{i}.joint{j}.lower_limit, .upper_limit           rad (the pair is sorted)
    controller.torque.k{k}.finger{i}.joint{j}              N m, torque policy
    controller.target.k{k}.finger{i}.joint{j}              rad, pd keyframes
    controller.kp.finger{i}.joint{j}, controller.kd...     pd gains

Only optimized values appear (a value with equal bounds is fixed).

Normalized space: the optimizer works on x in R^n, unbounded. Each value is folded into
[0, 1] by reflection at 0 and 1, y = fold(x), the triangle wave of period 2 (identity on
[0, 1], y(-x) = y(x), y(1 + x) = y(1 - x)); it is continuous, so a step of CMA-ES across a
bound moves the physical value back into the range instead of sticking to the bound (the
paper maps parameters "to a continuous function in the set range"). Then the physical value
is lower + y (upper - lower). The centre of the bounds is x = 0.5, where CMA-ES starts.

Seeded start (Tasks 1 and 2): `seed_mean()` takes each gene the task's seed design has from
the seed and every other gene from the centre of its bounds, as the paper starts CMA-ES. The
seed has every morphology gene (its structure is the task's), and its controller genes only
when its controller is of the task's policy kind: task1_torque.yaml seeds the hand from the
PD seed of Task 1 and starts its torques at the centre, never reading the seed's target
angles as torques.

Palm placement (beyond the paper): where the task gives bounds on `hand.base_position` or
`hand.base_yaw`, each axis and the yaw of non-zero width is a gene, and the Design's
HandDesign carries the decoded base position and yaw (its fixed axes the task's values), so
the simulators, the export and the pictures place the palm there (core.sim.hand.hand_model).
Where the task fixes them (the default, every preset), the HandDesign carries None and the
genome is the one it always was.

Decoding also keeps the Design physical: each joint's two limit genes are sorted into
lower <= upper, and the initial angle is clipped into the joint's limits.
"""

from dataclasses import dataclass
from typing import Mapping, Optional

from hand_codesign.core.design import (ControllerDesign, Design, FingerDesign, HandDesign,
                                       JointDesign)
from hand_codesign.core.task.parts import Bounds, TaskError
import numpy as np


def fold(x):
    """Return x folded into [0, 1] by reflection (period-2 triangle wave, continuous)."""
    y = np.mod(np.asarray(x, dtype=float), 2.0)
    return np.where(y > 1.0, 2.0 - y, y)


@dataclass(frozen=True)
class _Gene:
    """Marks a Design value taken from the genome's physical vector at `index`."""

    index: int


def _value(source, physical):
    return physical[source.index] if isinstance(source, _Gene) else source


class GenomeSpec:
    """
    The named genes of one task and hand structure, with physical bounds.

    Attributes: names (list of str), size, lower and upper (np.ndarray, physical units),
    structure (joints per finger), policy_kind ('torque' | 'pd').
    """

    def __init__(self, task):
        self.structure = tuple(task.structure)
        self.policy_kind = task.policy.kind
        self.num_knots = task.policy.num_knots
        self._builder = _Builder(task)
        names, lower, upper = self._builder.genes()
        self.names = names
        self.lower = np.array(lower, dtype=float)
        self.upper = np.array(upper, dtype=float)
        # the seed design's physical value of each gene (nan: the seed has none)
        self.seed_values = np.array(self._builder.seed_values, dtype=float)
        self.size = len(names)
        self._index = {name: index for index, name in enumerate(names)}

    def __repr__(self):
        return f'GenomeSpec(structure={self.structure}, size={self.size})'

    def index(self, name):
        """Return the position of gene `name`."""
        return self._index[name]

    def indices(self, prefix):
        """Return the indices of the genes whose names start with `prefix`, e.g. 'finger1.'."""
        return np.array([i for i, name in enumerate(self.names) if name.startswith(prefix)],
                        dtype=int)

    def initial_mean(self):
        """Return the normalized centre of the bounds (all 0.5), where CMA-ES starts."""
        return np.full(self.size, 0.5)

    def seed_mean(self):
        """
        Return the normalized start of a seeded search, or None without a seed design.

        A gene the seed has starts at the seed's value (outside [0, 1] if the seed lies
        outside the gene's bounds; decoding folds it back), every other gene at the centre.
        """
        if self._builder.task.seed_design is None:
            return None
        seeded = ~np.isnan(self.seed_values)
        return np.where(seeded, (self.seed_values - self.lower) / (self.upper - self.lower),
                        0.5)

    def to_physical(self, x):
        """Return the physical value of every gene of normalized genome x."""
        x = np.asarray(x, dtype=float)
        if x.shape != (self.size,):
            raise ValueError(f'genome of shape {x.shape}; expected ({self.size},) for '
                             f'structure {list(self.structure)}')
        return self.lower + fold(x) * (self.upper - self.lower)

    def values(self, x):
        """Return {gene name: physical value} of normalized genome x (limits unsorted)."""
        return dict(zip(self.names, self.to_physical(x).tolist()))

    def design_values(self, x):
        """
        Return {gene name: physical value} as the Design of x holds them.

        Unlike `values`, each joint's limit pair is sorted and its initial angle clipped into
        the limits: what a person reading a report or building the hand needs.
        """
        return dict(zip(self.names, self._builder.extract(self.decode(x)).tolist()))

    def decode(self, x) -> Design:
        """Return the Design of normalized genome x (any real values; see the module doc)."""
        return self._builder.design(self.to_physical(x))

    def encode(self, design):
        """
        Return the normalized genome of a Design or of a {gene name: physical value} map.

        The inverse of decode for values inside the bounds (and initial angles inside the
        limits); values outside the bounds give x outside [0, 1].
        """
        if isinstance(design, Design):
            physical = self._builder.extract(design)
        elif isinstance(design, Mapping):
            missing = [name for name in self.names if name not in design]
            if missing:
                raise ValueError(f'no value for gene {missing[0]!r}')
            physical = np.array([float(design[name]) for name in self.names])
        else:
            raise TypeError('encode takes a Design or a mapping of gene names to values')
        width = self.upper - self.lower
        return (np.asarray(physical, dtype=float) - self.lower) / width


def genome_spec(task) -> GenomeSpec:
    """Return the GenomeSpec of the task's hand structure and policy."""
    return GenomeSpec(task)


def decode(x, task) -> Design:
    """Return the Design of normalized genome x on `task`."""
    return genome_spec(task).decode(x)


def objective_names(task):
    """Return the objective names in Evaluation order: position_1.., then orientation_1.."""
    return list(task.objective_names)


class _Builder:
    """Resolves every Design value of a task to a gene or a fixed value."""

    def __init__(self, task):
        self.task = task
        self.names, self.lower, self.upper, self.seed_values = [], [], [], []
        seed = task.seed_design
        morphology = task.morphology
        self.friction = self.source('hand.friction', 'morphology.friction',
                                    morphology.friction, 0, None,
                                    seed.hand.friction if seed else None, minimum=0.0)
        self.placement = self.placement_sources(seed)
        self.fingers = []
        for finger, joints in enumerate(task.structure):
            self.fingers.append(self.finger_sources(finger, joints))
        self.controller = self.controller_sources()

    def genes(self):
        return list(self.names), list(self.lower), list(self.upper)

    # ---- resolving settings

    def source(self, name, key, setting, finger, joint, seed_value, joints=1, minimum=None,
               limit_index=None):
        """Return a _Gene or a fixed float for one value and register the gene."""
        mode = setting.mode
        if mode == 'none':
            return None
        if mode in ('seed', 'fixed'):
            if mode == 'seed':
                value = seed_value
            else:
                entry = setting.entry(finger)
                if isinstance(entry, Bounds):  # joint limits: a fixed pair
                    value = (entry.lower, entry.upper)[limit_index]
                elif isinstance(entry, tuple):
                    value = entry[joint]
                else:
                    value = entry
            if value is not None and minimum is not None and value < minimum:
                self.fail(key, f'a value >= {minimum} for {name}, got {value!r}')
            return value
        if mode == 'delta':
            if seed_value is None:
                self.fail(key, f'a seed value to add the delta to for {name} (the seed design '
                          'has none)')
            delta = setting.values[0]
            bounds = Bounds(seed_value + delta.lower, seed_value + delta.upper)
        else:
            bounds = setting.entry(finger)
            if setting.per_finger_total:
                bounds = Bounds(bounds.lower / joints, bounds.upper / joints)
        if minimum is not None and bounds.lower < minimum:
            self.fail(key, f'bounds >= {minimum} for {name}, got [{bounds.lower:.6g}, '
                      f'{bounds.upper:.6g}]')
        return self.gene(name, bounds, seed_value)

    def gene(self, name, bounds, seed_value):
        """Return a _Gene of `name` within `bounds` (registered), or the value of a point."""
        if bounds.width == 0:
            return bounds.lower
        self.names.append(name)
        self.lower.append(bounds.lower)
        self.upper.append(bounds.upper)
        self.seed_values.append(float('nan') if seed_value is None else float(seed_value))
        return _Gene(len(self.names) - 1)

    def fail(self, key, expected):
        raise TaskError(f'{self.task.source}: {key}: expected {expected}')

    def placement_sources(self, seed):
        """Return (three base position sources, base yaw source), or None if fixed."""
        hand = self.task.hand
        if not hand.placement_searched:
            return None
        seed_hand = seed.hand if seed is not None else None
        seed_position = getattr(seed_hand, 'base_position', None)
        seed_yaw = getattr(seed_hand, 'base_yaw', None)
        ranges = hand.base_position_bounds or tuple(
            Bounds(value, value) for value in hand.base_position)
        position = tuple(
            self.gene(f'hand.base_position_{axis}', bounds,
                      None if seed_position is None else seed_position[index])
            for index, (axis, bounds) in enumerate(zip('xyz', ranges)))
        yaw_range = hand.base_yaw_bounds or Bounds(hand.base_yaw, hand.base_yaw)
        yaw = self.gene('hand.base_yaw', yaw_range, seed_yaw)
        return position, yaw

    def finger_sources(self, finger, joints):
        morphology = self.task.morphology
        seed = self.seed_finger(finger)
        prefix = f'finger{finger}'
        position = tuple(
            self.source(f'{prefix}.position_{axis}', f'morphology.finger_position_{axis}',
                        getattr(morphology, f'finger_position_{axis}'), finger, None,
                        seed.position[index] if seed else None)
            for index, axis in enumerate('xz'))
        lengths, joint_sources = [], []
        for joint in range(joints):
            seed_joint = seed.joints[joint] if seed else None
            lengths.append(self.source(
                f'{prefix}.segment{joint}.length', 'morphology.segment_length',
                morphology.segment_length, finger, joint,
                seed.segment_lengths[joint] if seed else None, joints=joints, minimum=1e-4))
            name = f'{prefix}.joint{joint}'
            initial = self.source(f'{name}.initial_angle', 'morphology.initial_angle',
                                  morphology.initial_angle, finger, joint,
                                  seed_joint.initial_angle if seed_joint else None)
            axis = self.source(f'{name}.axis_angle', 'morphology.axis_angle',
                               morphology.axis_angle, finger, joint,
                               seed_joint.axis_angle if seed_joint else None)
            limits = tuple(
                self.source(f'{name}.{side}_limit', 'morphology.joint_limits',
                            morphology.joint_limits, finger, joint,
                            getattr(seed_joint, f'{side}_limit') if seed_joint else None,
                            limit_index=index)
                for index, side in enumerate(('lower', 'upper')))
            joint_sources.append((axis, initial, limits))
        return position, lengths, joint_sources

    def seed_finger(self, finger):
        seed = self.task.seed_design
        return seed.hand.fingers[finger] if seed is not None else None

    def seed_controller(self, name):
        seed = self.task.seed_design
        if seed is None or seed.controller.kind != self.task.policy.kind:
            return None
        return seed.controller.values if name in ('torque', 'target') else \
            getattr(seed.controller, name)

    def joint_order(self):
        """Yield (finger, joint, global joint index) base to tip, finger by finger."""
        index = 0
        for finger, joints in enumerate(self.task.structure):
            for joint in range(joints):
                yield finger, joint, index
                index += 1

    def controller_sources(self):
        policy = self.task.policy
        rows = []
        name = 'torque' if policy.kind == 'torque' else 'target'
        seed_rows = self.seed_controller(name)
        for knot in range(policy.num_knots):
            row = []
            for finger, joint, index in self.joint_order():
                row.append(self.source(
                    f'controller.{name}.k{knot}.finger{finger}.joint{joint}',
                    f'policy.{name}', getattr(policy, name), finger, joint,
                    None if seed_rows is None else float(seed_rows[knot][index])))
            rows.append(row)
        gains = {}
        if policy.kind == 'pd':
            for gain in ('kp', 'kd'):
                seed_gains = self.seed_controller(gain)
                gains[gain] = [self.source(
                    f'controller.{gain}.finger{finger}.joint{joint}', f'policy.{gain}',
                    getattr(policy, gain), finger, joint,
                    None if seed_gains is None else float(seed_gains[index]), minimum=0.0)
                    for finger, joint, index in self.joint_order()]
        return rows, gains

    # ---- building and reading Designs

    def design(self, physical):
        fingers = []
        for position, lengths, joint_sources in self.fingers:
            joints = []
            for axis, initial, limits in joint_sources:
                lower, upper = (_value(limit, physical) for limit in limits)
                angle = float(_value(initial, physical))
                if lower is not None and upper is not None:
                    lower, upper = min(lower, upper), max(lower, upper)
                    angle = min(max(angle, lower), upper)
                    lower, upper = float(lower), float(upper)
                else:
                    lower = upper = None
                joints.append(JointDesign(axis_angle=float(_value(axis, physical)),
                                          initial_angle=angle, lower_limit=lower,
                                          upper_limit=upper))
            fingers.append(FingerDesign(
                position=tuple(float(_value(p, physical)) for p in position),
                segment_lengths=tuple(float(_value(s, physical)) for s in lengths),
                joints=tuple(joints)))
        placed = {}
        if self.placement is not None:
            position, yaw = self.placement
            placed = {'base_position': tuple(float(_value(p, physical)) for p in position),
                      'base_yaw': float(_value(yaw, physical))}
        hand = HandDesign(fingers=tuple(fingers),
                          friction=float(_value(self.friction, physical)), **placed)
        rows, gains = self.controller
        values = np.array([[_value(s, physical) for s in row] for row in rows], dtype=float)
        kp, kd = (None if name not in gains else
                  np.array([_value(s, physical) for s in gains[name]], dtype=float)
                  for name in ('kp', 'kd'))
        return Design(hand=hand, controller=ControllerDesign(
            kind=self.task.policy.kind, values=values, kp=kp, kd=kd))

    def extract(self, design):
        """Return the physical gene vector that a Design holds."""
        if design.hand.structure != tuple(self.task.structure):
            raise ValueError(f'design of structure {list(design.hand.structure)}; expected '
                             f'{list(self.task.structure)}')
        physical = np.full(len(self.names), np.nan)

        def put(source, value):
            if isinstance(source, _Gene):
                if value is None:
                    raise ValueError(f'design has no value for gene {self.names[source.index]}')
                physical[source.index] = value

        put(self.friction, design.hand.friction)
        if self.placement is not None:
            # a design placed nowhere (a seed, a fixed task's) stands at the nominal place
            hand = self.task.hand
            position = design.hand.base_position or hand.base_position
            yaw = hand.base_yaw if design.hand.base_yaw is None else design.hand.base_yaw
            for source, value in zip(self.placement[0], position):
                put(source, value)
            put(self.placement[1], yaw)
        for sources, finger in zip(self.fingers, design.hand.fingers):
            position, lengths, joint_sources = sources
            for source, value in zip(position, finger.position):
                put(source, value)
            for source, value in zip(lengths, finger.segment_lengths):
                put(source, value)
            for (axis, initial, limits), joint in zip(joint_sources, finger.joints):
                put(axis, joint.axis_angle)
                put(initial, joint.initial_angle)
                put(limits[0], joint.lower_limit)
                put(limits[1], joint.upper_limit)
        rows, gains = self.controller
        controller = design.controller
        for knot, row in enumerate(rows):
            for index, source in enumerate(row):
                put(source, controller.values[knot][index])
        for name, sources in gains.items():
            for index, source in enumerate(sources):
                put(source, getattr(controller, name)[index])
        return physical


def seed_genome(task) -> Optional[np.ndarray]:
    """Return where a seeded search of the task starts (GenomeSpec.seed_mean), or None."""
    return genome_spec(task).seed_mean()
