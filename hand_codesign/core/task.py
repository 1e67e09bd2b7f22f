"""
The task specification: a YAML file, validated into a frozen tree of dataclasses.

A task says what the hand must do with one object (section III.A of the paper), which hand
parameters and controller values the optimizer searches and within which bounds (III.B), how
the result is scored (III.C) and with which budget. All values are SI units: metres, radians,
kilograms, newton metres, seconds. Where the YAML takes an angle, it also takes the strings
`pi`, `-pi/2`, `2*pi/3`... for readability.

Frames: the world is z-up with the ground plane at z = 0. The hand's fixed base (the palm
centre) sits at `hand.base_position` with `hand.base_orientation` (quaternion x, y, z, w); in
the hand frame the palm's normal is +y and fingers attach at (x, z) on the palm (see
hand_codesign.core.design). Goals are object poses in the world frame.

Schema (every key is required unless marked optional; unknown keys are errors)::

    name: task5                      # identifies the task in runs, bags and plots
    description: ...                 # optional, free text
    seed: 0                          # seeds the world states and the optimizer
    time_step: 0.005                 # physics step, s
    duration: 1.5                    # simulated time of one rollout, s
    object:
      shape: box                     # sphere | box | capsule
      size: [0.04, 0.04, 0.04]       # box only: full edge lengths, m
      radius: 0.02                   # sphere and capsule only, m
      length: 0.15                   # capsule only: its cylinder's length (caps excluded), m
      mass: 0.03                     # kg, > 0
      friction: 0.3                  # lateral friction coefficient, >= 0
      start: plane                   # plane: resting on the ground | midair
      position: [0, 0, 0.02]         # nominal centre; on the plane z must be the resting height
      orientation: [0, 0, 0, 1]      # quaternion x, y, z, w, or {axis: [0, 0, 1], angle: 0.3}
    hand:
      structure: [2, 2]              # joints per finger; optional when `hierarchy` is given
      base_position: [0, 0, 0.17]
      base_orientation: [-0.7071068, 0, 0, 0.7071068]   # or {axis: ..., angle: ...}
      palm_size: [0.16, 0.01, 0.08]  # full extents along the hand's x, y (normal), z
      palm_mass: 0.1                 # optional, kg (the palm is fixed; used for export)
      segment_radius: 0.007          # capsule radius of every finger segment, m
      segment_density: 1000          # kg / m^3 of the segments
    goals:
      distance: euclidean            # euclidean | manhattan, for position goals (eq. 3)
      samples_per_second: 10         # optional: spacing of a trajectory's interpolated goals
      relative_to_start: false       # optional: true moves each world's goals with its start
      position:                      # goals i = 1..n, strictly increasing times (may be [])
        - {time: 1.5, position: [0, 0, 0.02], trajectory: false}
      orientation:                   # goals i = 1..m (may be []); at least one goal in all
        - {time: 1.5, orientation: {axis: [0, 0, 1], angle: 0.785}, trajectory: true}
    randomization:                   # domain randomization, uniform in each range
      position: {x: [-0.005, 0.005], y: [-0.005, 0.005], z: [0, 0]}   # delta, m, world axes
      orientation: {axis: [0, 0, 1], range: [-0.4, 0.4]}             # delta angle, rad
      friction: [-0.1, 0.1]          # delta added to object.friction
      scale: [0.66, 1.5]             # factor on every object dimension
      mass: [0.66, 1.5]              # factor on object.mass
    num_world_states: 8
    morphology:                      # each: a parameter setting (see below)
      initial_angle: {bounds: [-pi/2, pi/2]}
      finger_position_x: {fixed: [-0.055, 0.055]}
      finger_position_z: {fixed: 0.0}
      segment_length: {bounds: [0.04, 0.09]}
      axis_angle: {fixed: pi/2}
      joint_limits: {bounds: [-pi/2, pi/2]}   # or none: the joints have no limits
      friction: {fixed: 0.8}
    policy:                          # kind torque (section III.B) ...
      kind: torque
      duration: 1.5                  # s; zero torque (plus gravity compensation) afterwards
      gravity_compensation: false    # optional (default false for torque, true for pd)
      mode: constant                 # constant: `knots` equal intervals | interpolated
      knots: 2                       # K torques per joint
      torque: {bounds: [-0.01, 0.01]}
    # policy: {kind: pd, duration: 2.0, keyframe_times: [0.5, 1.0, 2.0],
    #          target: {bounds: [-pi/2, pi/2]}, kp: {bounds: [1, 100]}, kd: {bounds: [0.1, 10]}}
    torque_penalty: {threshold: 0.008, weight: 0.5}     # optional: eq. (2) tau_p and w
    early_termination: {distance: 0.02, angle: 0.3}     # optional: eq. (6) d_s, theta_s;
                                                        # checks_per_second: 10 (optional)
    weights: {position: 1.0, orientation: 0.1}          # optional: w_p, w_r of the fitness
    physics: {solver_iterations: 50, contact_breaking_threshold: 0.02}   # optional: Bullet's
                                     # settings; these defaults reproduce the paper's runs
    optimizer:
      algorithm: cma                 # cma (weighted sum) | mocma (Pareto front)
      iterations: 100                # generations (per hand structure)
      population: 80
      initial_sigma: 0.1             # optional, in the normalized genome space
    hierarchy:                       # optional: search hand structures bottom-up (Fig. 1)
      start: [1]
      stop_structure: [2, 3]         # optional: last structure; or max_fingers/max_joints
      max_fingers: 3                 # optional
      max_joints: 3                  # optional, per finger
      position_threshold: 0.005      # stop when the best design's errors are below both
      orientation_threshold: 0.05
      evaluation_world_states: 64    # worlds the best design of each structure is tested on
    seed_design: task1_seed.yaml     # optional: a starting design (seeded search, Tasks 1/2),
                                     # inline or a file path relative to this task file

A parameter setting is one of:

- `{fixed: v}`: not optimized. `v` is one value for every finger (and joint), or a list with
  one entry per finger, each a value or (for per-joint parameters) a list per joint.
- `{bounds: [lower, upper]}`: optimized within bounds, the same for every finger and joint,
  or `{bounds: [[l0, u0], [l1, u1], ...]}` with one pair per finger. `segment_length` also
  takes `per_finger_total: true`: the bounds are for the whole finger and each segment gets
  them divided by that finger's number of joints (Task 4). Equal bounds fix the value.
- `{delta: [lower, upper]}`: optimized within the seed design's value plus the delta
  (Table I's `*`); needs `seed_design`.
- `seed`: not optimized, the seed design's value. `joint_limits` also takes `none`.

The torque values of a torque policy and the target angles, kp and kd of a pd policy take the
same settings (per finger, applying to all its joints). Joint limit bounds apply to both the
lower and the upper limit; the genome sorts each pair.

A seed design (YAML mapping) gives every value of a Design (hand_codesign.core.design)::

    friction: 0.9
    fingers:
      - position: [x, z]
        segment_lengths: [l0, l1]
        joints:
          - {axis_angle: 0, initial_angle: 0.1, lower_limit: -1, upper_limit: 1}   # limits
          - {axis_angle: 0, initial_angle: 0.2}                                     # optional
    controller: {kind: pd, values: [[...], ...], kp: [...], kd: [...]}    # rows = knots

Policies: a torque policy with mode `constant` holds torque k over [k D / K, (k + 1) D / K);
mode `interpolated` places torque k at time k D / (K - 1) and interpolates linearly (D the
policy duration, K the knots). A pd policy tracks, with equation (1), targets interpolated
linearly from the initial joint angles at t = 0 through keyframe k at keyframe_times[k],
holding the last one afterwards.
"""

import dataclasses
from dataclasses import dataclass
import math
import os
import re
from typing import Any, Optional, Tuple

from hand_codesign.core.design import (ControllerDesign, Design, FingerDesign, HandDesign,
                                       JointDesign)
import numpy as np
import yaml

SHAPES = ('sphere', 'box', 'capsule')
STARTS = ('plane', 'midair')
DISTANCES = ('euclidean', 'manhattan')
ALGORITHMS = ('cma', 'mocma')
POLICY_KINDS = ('torque', 'pd')
TORQUE_MODES = ('constant', 'interpolated')
PARAMETER_MODES = ('fixed', 'bounds', 'delta', 'seed', 'none')
MORPHOLOGY_PARAMETERS = ('initial_angle', 'finger_position_x', 'finger_position_z',
                         'segment_length', 'axis_angle', 'joint_limits', 'friction')
RESTING_TOLERANCE = 1e-4  # m: how far a plane start's z may be from the resting height


class TaskError(ValueError):
    """A task file is invalid; the message names the file, the dotted key and the fix."""


@dataclass(frozen=True)
class Bounds:
    """A closed interval [lower, upper] with lower <= upper."""

    lower: float
    upper: float

    @property
    def width(self):
        return self.upper - self.lower

    @property
    def centre(self):
        return (self.lower + self.upper) / 2


@dataclass(frozen=True)
class ObjectSpec:
    """The manipulated object, nominal (before domain randomization)."""

    shape: str  # 'sphere' | 'box' | 'capsule'
    mass: float  # kg
    friction: float
    start: str  # 'plane' | 'midair'
    position: Tuple[float, float, float]  # world frame, m
    orientation: Tuple[float, float, float, float]  # unit quaternion x, y, z, w
    size: Optional[Tuple[float, float, float]] = None  # box: full edge lengths
    radius: Optional[float] = None  # sphere, capsule
    length: Optional[float] = None  # capsule: cylinder length, caps excluded (Bullet's height)


@dataclass(frozen=True)
class HandSpec:
    """Where the hand is and the sizes the genome does not optimize."""

    base_position: Tuple[float, float, float]
    base_orientation: Tuple[float, float, float, float]  # x, y, z, w
    palm_size: Tuple[float, float, float]  # full extents along the hand's x, y, z
    segment_radius: float
    segment_density: float  # kg / m^3
    palm_mass: float = 0.1


@dataclass(frozen=True)
class PositionGoal:
    """Object position `position` (world, m) wanted at `time` (s)."""

    time: float
    position: Tuple[float, float, float]
    trajectory: bool  # also score interpolated goals from the previous goal (III.C)


@dataclass(frozen=True)
class OrientationGoal:
    """Object orientation `orientation` (quaternion x, y, z, w) wanted at `time` (s)."""

    time: float
    orientation: Tuple[float, float, float, float]
    trajectory: bool


@dataclass(frozen=True)
class GoalSpec:
    """The position and orientation goals; goal 0 is the object's nominal start pose."""

    distance: str  # 'euclidean' | 'manhattan'
    position: Tuple[PositionGoal, ...]
    orientation: Tuple[OrientationGoal, ...]
    samples_per_second: float = 10.0
    # False: goals are absolute world poses. True: goals are given for the nominal start and
    # each world's goals move with its start (shifted by its position offset, turned by its
    # orientation delta), so randomizing the start never counts as an error by itself.
    relative_to_start: bool = False


@dataclass(frozen=True)
class RandomizationSpec:
    """Domain randomization ranges; each world draws every quantity uniformly."""

    position: Tuple[Bounds, Bounds, Bounds]  # delta along world x, y, z, m
    orientation_axis: Tuple[float, float, float]  # unit vector, world frame
    orientation: Bounds  # delta angle about orientation_axis, rad
    friction: Bounds  # delta added to the object's friction
    scale: Bounds  # factor on every object dimension
    mass: Bounds  # factor on the object's mass

    def quantities(self):
        """Return (name, Bounds) of all seven quantities in WorldState order."""
        return (('position_x', self.position[0]), ('position_y', self.position[1]),
                ('position_z', self.position[2]), ('orientation', self.orientation),
                ('friction', self.friction), ('scale', self.scale), ('mass', self.mass))


@dataclass(frozen=True)
class ParameterSpec:
    """
    How one parameter is set: fixed, optimized within bounds or a delta, or from the seed.

    `values` holds, per mode: fixed -> one entry per finger (a float, or a tuple of floats
    per joint), or a single entry for all fingers; bounds -> one Bounds per finger or a single
    one; delta -> a single Bounds; seed / none -> empty.
    """

    mode: str  # 'fixed' | 'bounds' | 'delta' | 'seed' | 'none'
    values: Tuple[Any, ...] = ()
    per_finger_total: bool = False  # bounds of segment_length: for the whole finger

    def entry(self, finger):
        """Return the entry of finger `finger` (the single entry if only one is given)."""
        return self.values[0] if len(self.values) == 1 else self.values[finger]


@dataclass(frozen=True)
class MorphologySpec:
    """Settings of the hand parameters of section III.B (Table I, morphology rows)."""

    initial_angle: ParameterSpec  # per joint, rad
    finger_position_x: ParameterSpec  # per finger, m, hand frame
    finger_position_z: ParameterSpec
    segment_length: ParameterSpec  # per joint (segment), m
    axis_angle: ParameterSpec  # per joint, rad
    joint_limits: ParameterSpec  # per joint, rad; mode 'none': no limits
    friction: ParameterSpec  # one for the hand


@dataclass(frozen=True)
class PolicySpec:
    """The control policy and its bounds; fields of the other kind are None."""

    kind: str  # 'torque' | 'pd'
    duration: float  # s
    gravity_compensation: bool
    mode: Optional[str] = None  # torque: 'constant' | 'interpolated'
    knots: Optional[int] = None  # torque: K values per joint
    torque: Optional[ParameterSpec] = None  # torque: N m per joint and knot
    keyframe_times: Optional[Tuple[float, ...]] = None  # pd: s, strictly increasing, > 0
    target: Optional[ParameterSpec] = None  # pd: target joint angles, rad
    kp: Optional[ParameterSpec] = None  # pd: p coefficient per joint
    kd: Optional[ParameterSpec] = None  # pd: d coefficient per joint

    @property
    def num_knots(self):
        """Return the rows of ControllerDesign.values: K torques or keyframes."""
        return self.knots if self.kind == 'torque' else len(self.keyframe_times)


@dataclass(frozen=True)
class TorquePenaltySpec:
    """Equation (2): weight * (max |tau| - threshold) when max |tau| > threshold."""

    threshold: float  # tau_p, N m
    weight: float  # w in (0, 1)


@dataclass(frozen=True)
class EarlyTerminationSpec:
    """Equation (6): stop a rollout when a goal misses by more than d_s or theta_s."""

    distance: float  # d_s, m
    angle: float  # theta_s, rad
    checks_per_second: float = 10.0


@dataclass(frozen=True)
class PhysicsSpec:
    """
    Bullet settings that trade accuracy for speed; the defaults are those of Table I's runs.

    Fewer solver iterations and a shorter contact breaking threshold (Bullet keeps contact
    points up to that distance apart) make every step cheaper; bench/bench_physics.py measures
    how much faster and whether the ranking of designs and their robustness stay the same.
    """

    solver_iterations: int = 50
    contact_breaking_threshold: float = 0.02  # m


@dataclass(frozen=True)
class WeightsSpec:
    """Weights of the weighted-sum fitness: w_p for positions, w_r for orientations."""

    position: float = 1.0
    orientation: float = 0.1


@dataclass(frozen=True)
class HierarchySpec:
    """The bottom-up search over hand structures of Fig. 1."""

    start: Tuple[int, ...]
    position_threshold: float
    orientation_threshold: float
    evaluation_world_states: int
    stop_structure: Optional[Tuple[int, ...]] = None
    max_fingers: Optional[int] = None
    max_joints: Optional[int] = None


@dataclass(frozen=True)
class Task:
    """A whole task; see the module docstring for the YAML schema and units."""

    name: str
    seed: int
    time_step: float
    duration: float
    object_spec: ObjectSpec
    hand: HandSpec
    structure: Tuple[int, ...]
    goals: GoalSpec
    randomization: RandomizationSpec
    num_world_states: int
    morphology: MorphologySpec
    policy: PolicySpec
    algorithm: str
    iterations: int
    population: int
    initial_sigma: float = 0.1
    weights: WeightsSpec = WeightsSpec()
    physics: PhysicsSpec = PhysicsSpec()
    torque_penalty: Optional[TorquePenaltySpec] = None
    early_termination: Optional[EarlyTerminationSpec] = None
    hierarchy: Optional[HierarchySpec] = None
    seed_design: Optional[Design] = None
    description: str = ''
    source: str = '<task>'
    source_text: str = ''

    @property
    def num_steps(self):
        """Return the physics steps of one rollout."""
        return int(round(self.duration / self.time_step))

    @property
    def objective_names(self):
        """Return ('position_1', ..., 'orientation_1', ...): the objective vector's names."""
        return (tuple(f'position_{i + 1}' for i in range(len(self.goals.position)))
                + tuple(f'orientation_{i + 1}' for i in range(len(self.goals.orientation))))

    @property
    def objective_weights(self):
        """Return the fitness weights aligned with objective_names (w_p, then w_r)."""
        return np.array([self.weights.position] * len(self.goals.position)
                        + [self.weights.orientation] * len(self.goals.orientation))

    def replace(self, **changes):
        """
        Return a copy with some fields changed, validated like a loaded task.

        Typical: task.replace(seed=3, iterations=5, population=8, num_world_states=4,
        structure=(1, 2)). source_text stays the text as loaded.
        """
        unknown = sorted(set(changes) - {f.name for f in dataclasses.fields(self)})
        if unknown:
            raise TaskError(f'{self.source}: {unknown[0]}: not a Task field')
        if 'structure' in changes:
            changes['structure'] = tuple(changes['structure'])
        task = dataclasses.replace(self, **changes)
        _check_task(task)
        return task


# ---------------------------------------------------------------- loading


def load_task(path):
    """Read and validate a task file; raise TaskError naming the file and key on a mistake."""
    try:
        with open(path, encoding='utf-8') as stream:
            text = stream.read()
    except OSError as error:
        raise TaskError(f'{path}: cannot read the task file ({error.strerror})') from None
    return parse_task(text, source=str(path))


def parse_task(text, source='<task>'):
    """Validate YAML text into a Task; `source` names it in errors and resolves seed files."""
    try:
        document = yaml.safe_load(text)
    except yaml.YAMLError as error:
        raise TaskError(f'{source}: not valid YAML: {error}') from None
    reader = _Reader(source)
    task = reader.task(document)
    task = dataclasses.replace(task, source=source, source_text=text)
    _check_task(task)
    return task


class _Reader:
    """Walks the parsed YAML, checking keys and types with dotted paths for errors."""

    def __init__(self, source):
        self.source = source

    def fail(self, key, expected, value=None, got=True):
        text = f'{self.source}: {key}: expected {expected}'
        if got:
            text += f', got {value!r}'
        raise TaskError(text)

    # ---- generic values

    def mapping(self, value, key, required=(), optional=()):
        if not isinstance(value, dict):
            self.fail(key or 'top level', 'a mapping', value)
        for name in value:
            if name not in required and name not in optional:
                allowed = ', '.join(list(required) + list(optional))
                self.fail(_join(key, str(name)), f'no such key (allowed: {allowed})',
                          got=False)
        for name in required:
            if name not in value:
                self.fail(_join(key, name), 'this key (it is missing)', got=False)
        return value

    def number(self, value, key, minimum=None, positive=False, angle=False):
        number = _angle_expression(value) if angle and isinstance(value, str) else value
        if isinstance(number, bool) or not isinstance(number, (int, float)) \
                or not math.isfinite(number):
            self.fail(key, 'a number', value)
        number = float(number)
        if positive and not number > 0:
            self.fail(key, 'a positive number', value)
        if minimum is not None and number < minimum:
            self.fail(key, f'a number >= {minimum}', value)
        return number

    def integer(self, value, key, minimum=1):
        if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
            what = 'a positive integer' if minimum == 1 else f'an integer >= {minimum}'
            self.fail(key, what, value)
        return int(value)

    def boolean(self, value, key):
        if not isinstance(value, bool):
            self.fail(key, 'true or false', value)
        return value

    def choice(self, value, key, choices):
        if value not in choices:
            self.fail(key, 'one of ' + ', '.join(choices), value)
        return value

    def text(self, value, key):
        if not isinstance(value, str) or not value.strip():
            self.fail(key, 'a non-empty string', value)
        return value

    def vector(self, value, key, size, positive=False, angle=False):
        if not isinstance(value, list) or len(value) != size:
            self.fail(key, f'a list of {size} numbers', value)
        return tuple(self.number(item, f'{key}[{index}]', positive=positive, angle=angle)
                     for index, item in enumerate(value))

    def bounds(self, value, key, angle=False, minimum=None):
        if not isinstance(value, list) or len(value) != 2:
            self.fail(key, 'a pair [lower, upper]', value)
        lower, upper = (self.number(item, f'{key}[{index}]', angle=angle, minimum=minimum)
                        for index, item in enumerate(value))
        if lower > upper:
            self.fail(key, 'lower <= upper', value)
        return Bounds(lower, upper)

    def quaternion(self, value, key):
        if isinstance(value, dict):
            self.mapping(value, key, required=('axis', 'angle'))
            axis = self.unit_vector(value['axis'], _join(key, 'axis'))
            angle = self.number(value['angle'], _join(key, 'angle'), angle=True)
            return axis_angle_quaternion(axis, angle)
        if not isinstance(value, list) or len(value) != 4:
            self.fail(key, 'a quaternion [x, y, z, w] or {axis: [x, y, z], angle: rad}',
                      value)
        quaternion = np.array(self.vector(value, key, 4))
        norm = np.linalg.norm(quaternion)
        if norm < 1e-9:
            self.fail(key, 'a non-zero quaternion', value)
        return tuple(float(v) for v in quaternion / norm)

    def unit_vector(self, value, key):
        vector = np.array(self.vector(value, key, 3))
        norm = np.linalg.norm(vector)
        if norm < 1e-9:
            self.fail(key, 'a non-zero vector', value)
        return tuple(float(v) for v in vector / norm)

    def structure(self, value, key):
        if not isinstance(value, list) or not value:
            self.fail(key, 'a non-empty list of joints per finger, e.g. [2, 2]', value)
        return tuple(self.integer(item, f'{key}[{index}]') for index, item in enumerate(value))

    # ---- sections

    def task(self, document):
        top = self.mapping(document, '', required=(
            'name', 'seed', 'time_step', 'duration', 'object', 'hand', 'goals',
            'randomization', 'num_world_states', 'morphology', 'policy', 'optimizer'),
            optional=('description', 'torque_penalty', 'early_termination', 'weights',
                      'hierarchy', 'seed_design', 'physics'))
        hierarchy = (self.hierarchy(top['hierarchy'], 'hierarchy')
                     if top.get('hierarchy') is not None else None)
        hand, structure = self.hand(top['hand'], 'hand', hierarchy)
        optimizer = self.mapping(top['optimizer'], 'optimizer',
                                 required=('algorithm', 'iterations', 'population'),
                                 optional=('initial_sigma',))
        seed_design = None
        if top.get('seed_design') is not None:
            seed_design = self.seed_design(top['seed_design'], 'seed_design')
        description = top.get('description', '')
        if not isinstance(description, str):
            self.fail('description', 'a string', description)
        duration = self.number(top['duration'], 'duration', positive=True)
        return Task(
            name=self.text(top['name'], 'name'),
            description=description,
            seed=self.integer(top['seed'], 'seed', minimum=0),
            time_step=self.number(top['time_step'], 'time_step', positive=True),
            duration=duration,
            object_spec=self.object_spec(top['object'], 'object'),
            hand=hand,
            structure=structure,
            goals=self.goals(top['goals'], 'goals'),
            randomization=self.randomization(top['randomization'], 'randomization'),
            num_world_states=self.integer(top['num_world_states'], 'num_world_states'),
            morphology=self.morphology(top['morphology'], 'morphology'),
            policy=self.policy(top['policy'], 'policy'),
            algorithm=self.choice(optimizer['algorithm'], 'optimizer.algorithm', ALGORITHMS),
            iterations=self.integer(optimizer['iterations'], 'optimizer.iterations'),
            population=self.integer(optimizer['population'], 'optimizer.population'),
            initial_sigma=self.number(optimizer.get('initial_sigma', 0.1),
                                      'optimizer.initial_sigma', positive=True),
            weights=self.weights(top.get('weights', {}), 'weights'),
            physics=self.physics(top.get('physics', {}), 'physics'),
            torque_penalty=self.torque_penalty(top.get('torque_penalty'), 'torque_penalty'),
            early_termination=self.early_termination(top.get('early_termination'),
                                                     'early_termination'),
            hierarchy=hierarchy,
            seed_design=seed_design)

    def object_spec(self, value, key):
        section = self.mapping(value, key, required=(
            'shape', 'mass', 'friction', 'start', 'position', 'orientation'),
            optional=('size', 'radius', 'length'))
        shape = self.choice(section['shape'], _join(key, 'shape'), SHAPES)
        needed = {'sphere': ('radius',), 'box': ('size',), 'capsule': ('radius', 'length')}
        for name in ('size', 'radius', 'length'):
            if name in needed[shape] and name not in section:
                self.fail(_join(key, name), f'this key for a {shape} (it is missing)', got=False)
            if name not in needed[shape] and name in section:
                self.fail(_join(key, name), f'no {name} for a {shape} (a sphere takes radius, '
                          'a box size, a capsule radius and length)', got=False)
        size = section.get('size')
        if size is not None:
            size = (self.vector([size] * 3, _join(key, 'size'), 3, positive=True)
                    if not isinstance(size, list)
                    else self.vector(size, _join(key, 'size'), 3, positive=True))
        return ObjectSpec(
            shape=shape,
            size=size,
            radius=(self.number(section['radius'], _join(key, 'radius'), positive=True)
                    if 'radius' in section else None),
            length=(self.number(section['length'], _join(key, 'length'), positive=True)
                    if 'length' in section else None),
            mass=self.number(section['mass'], _join(key, 'mass'), positive=True),
            friction=self.number(section['friction'], _join(key, 'friction'), minimum=0),
            start=self.choice(section['start'], _join(key, 'start'), STARTS),
            position=self.vector(section['position'], _join(key, 'position'), 3),
            orientation=self.quaternion(section['orientation'], _join(key, 'orientation')))

    def hand(self, value, key, hierarchy):
        section = self.mapping(value, key, required=(
            'base_position', 'base_orientation', 'palm_size', 'segment_radius',
            'segment_density'), optional=('structure', 'palm_mass'))
        if 'structure' in section:
            structure = self.structure(section['structure'], _join(key, 'structure'))
        elif hierarchy is not None:
            structure = hierarchy.start
        else:
            self.fail(_join(key, 'structure'), 'this key (joints per finger, e.g. [2, 2]) '
                      'unless a hierarchy gives the start', got=False)
        spec = HandSpec(
            base_position=self.vector(section['base_position'], _join(key, 'base_position'),
                                      3),
            base_orientation=self.quaternion(section['base_orientation'],
                                             _join(key, 'base_orientation')),
            palm_size=self.vector(section['palm_size'], _join(key, 'palm_size'), 3,
                                  positive=True),
            segment_radius=self.number(section['segment_radius'],
                                       _join(key, 'segment_radius'), positive=True),
            segment_density=self.number(section['segment_density'],
                                        _join(key, 'segment_density'), positive=True),
            palm_mass=self.number(section.get('palm_mass', 0.1), _join(key, 'palm_mass'),
                                  positive=True))
        return spec, structure

    def goals(self, value, key):
        section = self.mapping(value, key, required=('distance', 'position', 'orientation'),
                               optional=('samples_per_second', 'relative_to_start'))
        position = self.goal_list(section['position'], _join(key, 'position'), 'position')
        orientation = self.goal_list(section['orientation'], _join(key, 'orientation'),
                                     'orientation')
        if not position and not orientation:
            self.fail(key, 'at least one position or orientation goal', got=False)
        return GoalSpec(
            distance=self.choice(section['distance'], _join(key, 'distance'), DISTANCES),
            position=position, orientation=orientation,
            samples_per_second=self.number(section.get('samples_per_second', 10.0),
                                           _join(key, 'samples_per_second'), positive=True),
            relative_to_start=self.boolean(section.get('relative_to_start', False),
                                           _join(key, 'relative_to_start')))

    def goal_list(self, value, key, kind):
        if not isinstance(value, list):
            self.fail(key, f'a list of {kind} goals (or [])', value)
        goals = []
        for index, item in enumerate(value):
            item_key = f'{key}[{index}]'
            item = self.mapping(item, item_key, required=('time', kind, 'trajectory'))
            time = self.number(item['time'], _join(item_key, 'time'), positive=True)
            if goals and time <= goals[-1].time:
                self.fail(_join(item_key, 'time'),
                          f"a time after the previous goal's {goals[-1].time}", item['time'])
            trajectory = self.boolean(item['trajectory'], _join(item_key, 'trajectory'))
            if kind == 'position':
                goals.append(PositionGoal(time, self.vector(item[kind], _join(item_key, kind),
                                                            3), trajectory))
            else:
                goals.append(OrientationGoal(time, self.quaternion(item[kind],
                                                                   _join(item_key, kind)),
                                             trajectory))
        return tuple(goals)

    def randomization(self, value, key):
        section = self.mapping(value, key, required=(
            'position', 'orientation', 'friction', 'scale', 'mass'))
        position_key = _join(key, 'position')
        position = self.mapping(section['position'], position_key, required=('x', 'y', 'z'))
        orientation_key = _join(key, 'orientation')
        orientation = self.mapping(section['orientation'], orientation_key,
                                   required=('axis', 'range'))
        scale = self.bounds(section['scale'], _join(key, 'scale'))
        mass = self.bounds(section['mass'], _join(key, 'mass'))
        for name, factor in (('scale', scale), ('mass', mass)):
            if not factor.lower > 0:
                self.fail(_join(key, name), 'positive factors', section[name])
        return RandomizationSpec(
            position=tuple(self.bounds(position[axis], _join(position_key, axis))
                           for axis in 'xyz'),
            orientation_axis=self.unit_vector(orientation['axis'],
                                              _join(orientation_key, 'axis')),
            orientation=self.bounds(orientation['range'], _join(orientation_key, 'range'),
                                    angle=True),
            friction=self.bounds(section['friction'], _join(key, 'friction')),
            scale=scale, mass=mass)

    def parameter(self, value, key, per_joint=False, angle=False, minimum=None,
                  allow_total=False, allow_none=False):
        if value in ('seed', 'none'):
            if value == 'none' and not allow_none:
                self.fail(key, 'a setting {fixed: ...}, {bounds: ...}, {delta: ...} or seed',
                          value)
            return ParameterSpec(value)
        optional = ('per_finger_total',) if allow_total else ()
        if not isinstance(value, dict) or len(set(value) - set(optional)) != 1:
            self.fail(key, 'one of {fixed: v}, {bounds: [lower, upper]}, '
                      '{delta: [lower, upper]}, seed' + (', none' if allow_none else ''), value)
        self.mapping(value, key, optional=('fixed', 'bounds', 'delta') + optional)
        per_finger_total = self.boolean(value.get('per_finger_total', False),
                                        _join(key, 'per_finger_total'))
        if 'delta' in value:
            return ParameterSpec('delta', (self.bounds(value['delta'], _join(key, 'delta'),
                                                       angle=angle),))
        if 'bounds' in value:
            entry_key = _join(key, 'bounds')
            entries = value['bounds']
            if isinstance(entries, list) and entries and isinstance(entries[0], list):
                values = tuple(self.bounds(item, f'{entry_key}[{index}]', angle=angle,
                                           minimum=minimum)
                               for index, item in enumerate(entries))
            else:
                values = (self.bounds(entries, entry_key, angle=angle, minimum=minimum),)
            return ParameterSpec('bounds', values, per_finger_total)
        if per_finger_total:
            self.fail(_join(key, 'per_finger_total'), 'only with bounds', got=False)
        return ParameterSpec('fixed', self.fixed_values(value['fixed'], _join(key, 'fixed'),
                                                        per_joint, angle, minimum))

    def fixed_values(self, value, key, per_joint, angle, minimum):
        def scalar(item, item_key):
            return self.number(item, item_key, angle=angle, minimum=minimum)

        if not isinstance(value, list):
            return (scalar(value, key),)
        if not value:
            self.fail(key, 'a value or a non-empty list per finger', value)
        values = []
        for index, item in enumerate(value):
            item_key = f'{key}[{index}]'
            if isinstance(item, list) and per_joint:
                values.append(tuple(scalar(v, f'{item_key}[{j}]') for j, v in enumerate(item)))
            else:
                values.append(scalar(item, item_key))
        return tuple(values)

    def morphology(self, value, key):
        section = self.mapping(value, key, required=MORPHOLOGY_PARAMETERS)

        def setting(name, **options):
            return self.parameter(section[name], _join(key, name), **options)

        return MorphologySpec(
            initial_angle=setting('initial_angle', per_joint=True, angle=True),
            finger_position_x=setting('finger_position_x'),
            finger_position_z=setting('finger_position_z'),
            segment_length=setting('segment_length', per_joint=True, allow_total=True),
            axis_angle=setting('axis_angle', per_joint=True, angle=True),
            joint_limits=self.joint_limits(section['joint_limits'],
                                           _join(key, 'joint_limits')),
            friction=setting('friction', minimum=0))

    def joint_limits(self, value, key):
        if isinstance(value, dict) and set(value) == {'fixed'}:
            # a fixed setting is a [lower, upper] pair, or one pair per finger
            raw, fixed_key = value['fixed'], _join(key, 'fixed')
            if isinstance(raw, list) and raw and isinstance(raw[0], list):
                return ParameterSpec('fixed', tuple(
                    self.bounds(pair, f'{fixed_key}[{index}]', angle=True)
                    for index, pair in enumerate(raw)))
            return ParameterSpec('fixed', (self.bounds(raw, fixed_key, angle=True),))
        return self.parameter(value, key, angle=True, allow_none=True)

    def policy(self, value, key):
        kind = self.choice(value.get('kind') if isinstance(value, dict) else value,
                           _join(key, 'kind'), POLICY_KINDS)
        common = ('kind', 'duration')
        if kind == 'torque':
            section = self.mapping(value, key, required=common + ('mode', 'knots', 'torque'),
                                   optional=('gravity_compensation',))
            return PolicySpec(
                kind=kind,
                duration=self.number(section['duration'], _join(key, 'duration'),
                                     positive=True),
                gravity_compensation=self.boolean(section.get('gravity_compensation', False),
                                                  _join(key, 'gravity_compensation')),
                mode=self.choice(section['mode'], _join(key, 'mode'), TORQUE_MODES),
                knots=self.integer(section['knots'], _join(key, 'knots')),
                torque=self.parameter(section['torque'], _join(key, 'torque')))
        section = self.mapping(value, key, required=common + ('keyframe_times', 'target', 'kp',
                                                              'kd'),
                               optional=('gravity_compensation',))
        times_key = _join(key, 'keyframe_times')
        times = section['keyframe_times']
        if not isinstance(times, list) or not times:
            self.fail(times_key, 'a non-empty list of times', times)
        times = tuple(self.number(t, f'{times_key}[{i}]', positive=True)
                      for i, t in enumerate(times))
        if any(b <= a for a, b in zip(times, times[1:])):
            self.fail(times_key, 'strictly increasing times', section['keyframe_times'])
        return PolicySpec(
            kind=kind,
            duration=self.number(section['duration'], _join(key, 'duration'), positive=True),
            gravity_compensation=self.boolean(section.get('gravity_compensation', True),
                                              _join(key, 'gravity_compensation')),
            keyframe_times=times,
            target=self.parameter(section['target'], _join(key, 'target'), angle=True),
            kp=self.parameter(section['kp'], _join(key, 'kp'), minimum=0),
            kd=self.parameter(section['kd'], _join(key, 'kd'), minimum=0))

    def torque_penalty(self, value, key):
        if value is None:
            return None
        section = self.mapping(value, key, required=('threshold', 'weight'))
        weight = self.number(section['weight'], _join(key, 'weight'), positive=True)
        if weight >= 1:
            self.fail(_join(key, 'weight'), 'a weight w in (0, 1)', section['weight'])
        return TorquePenaltySpec(
            threshold=self.number(section['threshold'], _join(key, 'threshold'), minimum=0),
            weight=weight)

    def early_termination(self, value, key):
        if value is None:
            return None
        section = self.mapping(value, key, required=('distance', 'angle'),
                               optional=('checks_per_second',))
        return EarlyTerminationSpec(
            distance=self.number(section['distance'], _join(key, 'distance'), positive=True),
            angle=self.number(section['angle'], _join(key, 'angle'), positive=True,
                              angle=True),
            checks_per_second=self.number(section.get('checks_per_second', 10.0),
                                          _join(key, 'checks_per_second'), positive=True))

    def physics(self, value, key):
        section = self.mapping(value, key, optional=('solver_iterations',
                                                     'contact_breaking_threshold'))
        default = PhysicsSpec()
        return PhysicsSpec(
            solver_iterations=self.integer(section.get('solver_iterations',
                                                       default.solver_iterations),
                                           _join(key, 'solver_iterations')),
            contact_breaking_threshold=self.number(
                section.get('contact_breaking_threshold', default.contact_breaking_threshold),
                _join(key, 'contact_breaking_threshold'), positive=True))

    def weights(self, value, key):
        section = self.mapping(value, key, optional=('position', 'orientation'))
        return WeightsSpec(
            position=self.number(section.get('position', 1.0), _join(key, 'position'),
                                 minimum=0),
            orientation=self.number(section.get('orientation', 0.1),
                                    _join(key, 'orientation'), minimum=0))

    def hierarchy(self, value, key):
        section = self.mapping(value, key, required=(
            'start', 'position_threshold', 'orientation_threshold', 'evaluation_world_states'),
            optional=('stop_structure', 'max_fingers', 'max_joints'))
        stop = section.get('stop_structure')
        return HierarchySpec(
            start=self.structure(section['start'], _join(key, 'start')),
            stop_structure=(None if stop is None
                            else self.structure(stop, _join(key, 'stop_structure'))),
            max_fingers=(None if section.get('max_fingers') is None
                         else self.integer(section['max_fingers'], _join(key, 'max_fingers'))),
            max_joints=(None if section.get('max_joints') is None
                        else self.integer(section['max_joints'], _join(key, 'max_joints'))),
            position_threshold=self.number(section['position_threshold'],
                                           _join(key, 'position_threshold'), minimum=0),
            orientation_threshold=self.number(section['orientation_threshold'],
                                              _join(key, 'orientation_threshold'),
                                              minimum=0, angle=True),
            evaluation_world_states=self.integer(section['evaluation_world_states'],
                                                 _join(key, 'evaluation_world_states')))

    def seed_design(self, value, key):
        if isinstance(value, str):
            base = os.path.dirname(self.source) if os.path.exists(self.source) else '.'
            path = os.path.join(base, value)
            try:
                with open(path, encoding='utf-8') as stream:
                    document = yaml.safe_load(stream)
            except OSError as error:
                self.fail(key, f'a readable seed design file ({error.strerror}: {path})',
                          value)
            except yaml.YAMLError as error:
                self.fail(key, f'a seed design file in valid YAML ({error})', value)
            return _Reader(path).design(document, '')
        return self.design(value, key)

    def design(self, value, key):
        section = self.mapping(value, key, required=('friction', 'fingers', 'controller'))
        fingers_key = _join(key, 'fingers')
        if not isinstance(section['fingers'], list) or not section['fingers']:
            self.fail(fingers_key, 'a non-empty list of fingers', section['fingers'])
        fingers = tuple(self.finger(item, f'{fingers_key}[{index}]')
                        for index, item in enumerate(section['fingers']))
        hand = HandDesign(fingers=fingers, friction=self.number(
            section['friction'], _join(key, 'friction'), minimum=0))
        controller = self.controller(section['controller'], _join(key, 'controller'),
                                     hand.num_joints)
        return Design(hand=hand, controller=controller)

    def finger(self, value, key):
        section = self.mapping(value, key, required=('position', 'segment_lengths', 'joints'))
        joints_key = _join(key, 'joints')
        if not isinstance(section['joints'], list) or not section['joints']:
            self.fail(joints_key, 'a non-empty list of joints', section['joints'])
        joints = tuple(self.joint(item, f'{joints_key}[{index}]')
                       for index, item in enumerate(section['joints']))
        lengths = self.vector(section['segment_lengths'], _join(key, 'segment_lengths'),
                              len(joints), positive=True)
        return FingerDesign(position=self.vector(section['position'], _join(key, 'position'),
                                                 2),
                            segment_lengths=lengths, joints=joints)

    def joint(self, value, key):
        section = self.mapping(value, key, required=('axis_angle', 'initial_angle'),
                               optional=('lower_limit', 'upper_limit'))
        if ('lower_limit' in section) != ('upper_limit' in section):
            self.fail(key, 'both lower_limit and upper_limit, or neither', got=False)
        limits = (None, None)
        if 'lower_limit' in section:
            pair = self.bounds([section['lower_limit'], section['upper_limit']],
                               _join(key, 'lower_limit/upper_limit'), angle=True)
            limits = (pair.lower, pair.upper)
        return JointDesign(
            axis_angle=self.number(section['axis_angle'], _join(key, 'axis_angle'),
                                   angle=True),
            initial_angle=self.number(section['initial_angle'], _join(key, 'initial_angle'),
                                      angle=True),
            lower_limit=limits[0], upper_limit=limits[1])

    def controller(self, value, key, num_joints):
        section = self.mapping(value, key, required=('kind', 'values'), optional=('kp', 'kd'))
        kind = self.choice(section['kind'], _join(key, 'kind'), POLICY_KINDS)
        values_key = _join(key, 'values')
        rows = section['values']
        if not isinstance(rows, list) or not rows:
            self.fail(values_key, f'a list of rows of {num_joints} values', rows)
        values = np.array([self.vector(row, f'{values_key}[{index}]', num_joints, angle=True)
                           for index, row in enumerate(rows)])
        gains = {}
        for name in ('kp', 'kd'):
            if kind == 'pd':
                if name not in section:
                    self.fail(_join(key, name), f'this key for a pd controller ({num_joints} '
                              'values)', got=False)
                gains[name] = np.array(self.vector(section[name], _join(key, name),
                                                   num_joints, positive=True))
            elif name in section:
                self.fail(_join(key, name), 'no gains for a torque controller', got=False)
        return ControllerDesign(kind=kind, values=values, kp=gains.get('kp'),
                                kd=gains.get('kd'))


def _join(prefix, name):
    return f'{prefix}.{name}' if prefix else name


_ANGLE = re.compile(r'^\s*(-)?\s*(?:(\d+(?:\.\d*)?)\s*\*\s*)?pi\s*(?:/\s*(\d+(?:\.\d*)?))?\s*$')


def _angle_expression(text):
    """Return the value of '[-][k*]pi[/d]' or the text itself when it is not one."""
    match = _ANGLE.match(text)
    if not match:
        return text
    sign, factor, divisor = match.groups()
    value = math.pi * float(factor or 1) / float(divisor or 1)
    return -value if sign else value


def axis_angle_quaternion(axis, angle):
    """Return the unit quaternion (x, y, z, w) rotating by `angle` about unit `axis`."""
    half = angle / 2
    sine = math.sin(half)
    return tuple(float(v) + 0.0 for v in (axis[0] * sine, axis[1] * sine, axis[2] * sine,
                                          math.cos(half)))


def resting_height(object_spec, scale=1.0, orientation=None):
    """
    Return the height of the object's centre above the plane when it rests on it.

    That is the object's extent below its centre along world z, for the object scaled by
    `scale` and turned to `orientation` (default: its nominal orientation).
    """
    rotation = _rotation_matrix(object_spec.orientation if orientation is None
                                else orientation)
    vertical = np.abs(rotation[2])  # |z-components| of the object's local axes
    if object_spec.shape == 'sphere':
        return object_spec.radius * scale
    if object_spec.shape == 'box':
        return float(np.dot(vertical, np.array(object_spec.size) / 2)) * scale
    return (object_spec.radius + vertical[2] * object_spec.length / 2) * scale


def _rotation_matrix(quaternion):
    x, y, z, w = quaternion
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


# ---------------------------------------------------------------- cross-field checks


def _check_task(task):
    """Check what spans several keys; raise TaskError naming the key to fix."""
    source = task.source

    def fail(key, expected):
        raise TaskError(f'{source}: {key}: expected {expected}')

    for name in ('seed', 'iterations', 'population', 'num_world_states'):
        value = getattr(task, name)
        minimum = 0 if name == 'seed' else 1
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) \
                or value < minimum:
            fail(name if name in ('seed', 'num_world_states') else f'optimizer.{name}',
                 f'an integer >= {minimum}, got {value!r}')
    if not task.structure or any(int(j) < 1 for j in task.structure):
        fail('hand.structure', f'a non-empty list of positive joint counts, got '
             f'{task.structure!r}')
    if task.algorithm not in ALGORITHMS:
        fail('optimizer.algorithm', f'one of {", ".join(ALGORITHMS)}, got {task.algorithm!r}')
    steps = task.duration / task.time_step
    if abs(steps - round(steps)) > 1e-6 or round(steps) < 1:
        fail('duration', f'a whole number of time steps ({task.time_step} s), got '
             f'{task.duration!r}')
    for kind in ('position', 'orientation'):
        for index, goal in enumerate(getattr(task.goals, kind)):
            if goal.time > task.duration + 1e-9:
                fail(f'goals.{kind}[{index}].time',
                     f'a time within the duration {task.duration} s, got {goal.time!r}')
    if task.policy.duration > task.duration + 1e-9:
        fail('policy.duration', f'at most the task duration {task.duration} s, got '
             f'{task.policy.duration!r}')
    if task.policy.kind == 'pd' and task.policy.keyframe_times[-1] > task.policy.duration:
        fail('policy.keyframe_times', f'times within policy.duration '
             f'{task.policy.duration} s, got {list(task.policy.keyframe_times)!r}')
    if task.policy.kind == 'torque' and task.policy.mode == 'interpolated' \
            and task.policy.knots < 2:
        fail('policy.knots', f'at least 2 knots to interpolate, got {task.policy.knots!r}')
    _check_object(task, fail)
    _check_settings(task, fail)
    if task.hierarchy is not None:
        _check_hierarchy(task.hierarchy, fail)


def _check_object(task, fail):
    spec = task.object_spec
    if spec.start == 'plane':
        height = resting_height(spec)
        if abs(spec.position[2] - height) > RESTING_TOLERANCE:
            fail('object.position', f'z = {height:.6g} for an object resting on the plane, '
                 f'got {spec.position[2]!r}')
        if task.randomization.position[2].width > 0:
            fail('randomization.position.z', '[0, 0] for an object starting on the plane, '
                 f'got [{task.randomization.position[2].lower}, '
                 f'{task.randomization.position[2].upper}]')
    if spec.friction + task.randomization.friction.lower < 0:
        fail('randomization.friction', 'deltas that keep the object friction >= 0, got '
             f'a lower delta of {task.randomization.friction.lower!r}')


def _settings(task):
    """Yield (dotted key, ParameterSpec) of every parameter setting of the task."""
    for name in MORPHOLOGY_PARAMETERS:
        yield f'morphology.{name}', getattr(task.morphology, name)
    for name in ('torque', 'target', 'kp', 'kd'):
        setting = getattr(task.policy, name)
        if setting is not None:
            yield f'policy.{name}', setting


def _check_settings(task, fail):
    fingers = len(task.structure)
    seed = task.seed_design
    if seed is not None and seed.hand.structure != task.structure:
        fail('hand.structure', f"the seed design's structure {list(seed.hand.structure)}, "
             f'got {list(task.structure)}')
    if seed is not None and seed.controller.kind != task.policy.kind \
            and any(s.mode in ('delta', 'seed') for k, s in _settings(task)
                    if k.startswith('policy.')):
        fail('seed_design.controller.kind', f'{task.policy.kind} for a policy set from the '
             f'seed, got {seed.controller.kind!r}')
    if seed is not None and seed.controller.kind == task.policy.kind \
            and len(seed.controller.values) != task.policy.num_knots:
        fail('seed_design.controller.values', f'{task.policy.num_knots} rows (the '
             f"policy's knots), got {len(seed.controller.values)}")
    for key, setting in _settings(task):
        if setting.mode in ('delta', 'seed') and seed is None:
            fail(key, 'a seed_design for a delta or seed setting (or use fixed or bounds)')
        if setting.mode in ('fixed', 'bounds') and len(setting.values) > 1 \
                and len(setting.values) < fingers:
            fail(key, f'one entry per finger ({fingers}), got {len(setting.values)}')
        if setting.mode == 'fixed':
            for finger, joints in enumerate(task.structure):
                entry = setting.entry(finger) if finger < len(setting.values) or \
                    len(setting.values) == 1 else None
                if isinstance(entry, tuple) and len(entry) != joints:
                    fail(key, f'{joints} values for finger {finger} (one per joint), got '
                         f'{len(entry)}')
        if setting.per_finger_total and key != 'morphology.segment_length':
            fail(key, 'per_finger_total only for segment_length')
    length = task.morphology.segment_length
    if length.mode == 'bounds' and any(b.lower <= 0 for b in length.values):
        fail('morphology.segment_length.bounds', 'positive lengths')


def _check_hierarchy(hierarchy, fail):
    if hierarchy.stop_structure is None and hierarchy.max_fingers is None:
        fail('hierarchy', 'stop_structure or max_fingers to end the search')
    if hierarchy.max_fingers is not None and len(hierarchy.start) > hierarchy.max_fingers:
        fail('hierarchy.start', f'at most max_fingers ({hierarchy.max_fingers}) fingers')
