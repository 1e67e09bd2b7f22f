"""
The parts of a Task, as the reader builds them: the task room's shared vocabulary.

Frozen dataclasses, the schema's constants and TaskError; the Task itself is in
hand_codesign.core.task.spec. Every key of a task file is a field here (or of the Task),
declared with core.task.schema.key: its meaning, unit, default, bounds or choices and how it
is read (docs/TASK.md is generated from them). This module imports only the schema of the task
room, so every other module of it (and the genome) can import it.
"""

import dataclasses
from dataclasses import dataclass
from typing import Any, Optional, Tuple

from hand_codesign.core.outcomes import OUTCOME_NAMES
from hand_codesign.core.rotations import rotation_matrix
from hand_codesign.core.task.schema import Depends, GIVEN, key
import numpy as np

SHAPES = ('sphere', 'box', 'capsule')
STARTS = ('plane', 'midair')
DISTANCES = ('euclidean', 'manhattan')
ALGORITHMS = ('cma', 'mocma', 'ipop-cma', 'bipop-cma', 'cma-mae', 'cma-me')
RESTART_ALGORITHMS = ('ipop-cma', 'bipop-cma')  # CMA-ES with restarts (core.search.restarts)
# which design of MO-CMA-ES's final Pareto front a run returns (core.search.optimizers.front_index)
FRONT_CHOICES = ('normalized', 'weighted')
QD_ALGORITHMS = ('cma-mae', 'cma-me')  # quality-diversity search (core.search.quality_diversity)
# the descriptors of a design an archive may span (core.task.descriptors)
DESCRIPTOR_NAMES = ('finger_length', 'length_asymmetry', 'joint_range', 'initial_angle',
                    'finger_spread', 'friction')
# and all it may span: those of the design, then those of its rollouts' outcome (core.outcomes)
ARCHIVE_DESCRIPTOR_NAMES = DESCRIPTOR_NAMES + OUTCOME_NAMES
POLICY_KINDS = ('torque', 'pd')
TORQUE_MODES = ('constant', 'interpolated')
PARAMETER_MODES = ('fixed', 'bounds', 'delta', 'seed', 'none')
MORPHOLOGY_PARAMETERS = ('initial_angle', 'finger_position_x', 'finger_position_z',
                         'segment_length', 'axis_angle', 'joint_limits', 'friction')
RESTING_TOLERANCE = 1e-4  # m: how far a plane start's z may be from the resting height
AXES = ('x', 'y', 'z')  # the world axes a position goal may measure
WORLD_AGGREGATES = ('mean', 'worst')  # worlds.aggregate: eq. (5)'s mean, or CVaR of the worst
ENGINES = ('pybullet', 'mujoco')  # physics.engine: core.sim.pybullet_sim or core.sim.mujoco_sim
# physics.engine_aggregate: the mean of the engines' objectives, or per objective the worse one
ENGINE_AGGREGATES = ('mean', 'worst')
# physics.contact: the object's contact parameters a world may draw (ContactSpec)
CONTACT_PARAMETERS = ('stiffness', 'damping', 'restitution')
WORLD_RESAMPLING = ('none', 'generation')  # worlds.resample: a fixed set, or a draw per generation
FINAL_CHECK = 5  # default worlds.final_check: the last generations whose bests are re-evaluated


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

    shape: str = key('the shape of the object', 'choice', choices=SHAPES)
    mass: float = key('its mass', 'number', unit='kg', positive=True)
    friction: float = key('its lateral friction coefficient', 'number', minimum=0)
    start: str = key('where it starts: resting on the plane, or in mid-air', 'choice',
                     choices=STARTS)
    position: Tuple[float, float, float] = key(
        'its nominal centre, world frame; resting on the plane, z is its resting height',
        'vector', unit='m', size=3)
    orientation: Tuple[float, float, float, float] = key(
        'its nominal orientation: a quaternion [x, y, z, w] or {axis: [x, y, z], angle: rad}',
        'quaternion')
    size: Optional[Tuple[float, float, float]] = key(
        "a box's full edge lengths (one number: a cube)", 'custom', unit='m', read='box_size',
        values='3 numbers, each > 0 (or one: a cube)',
        when=('shape', ('box',), 'for a {}'), field_default=None)
    radius: Optional[float] = key(
        "a sphere's or a capsule's radius", 'number', unit='m', positive=True,
        when=('shape', ('sphere', 'capsule'), 'for a {}'), field_default=None)
    length: Optional[float] = key(
        "a capsule's cylinder length, its caps excluded (Bullet's height)", 'number', unit='m',
        positive=True, when=('shape', ('capsule',), 'for a {}'), field_default=None)


@dataclass(frozen=True)
class HandSpec:
    """Where the hand is and the sizes the genome does not optimize."""

    # Fixed: the value; searched (beyond the paper): the centre of the bounds, the
    # bounds in base_position_bounds (core.task.genome makes them genes)
    base_position: Tuple[float, float, float] = key(
        "the palm centre's position, the hand's fixed base: [x, y, z], or searched within "
        '{bounds: [[x lower, x upper], [y lower, y upper], [z lower, z upper]]} (beyond the '
        'paper)', 'custom', unit='m', read='base_position',
        values='3 numbers, {fixed: 3 numbers} or {bounds: 3 pairs [lower, upper]}')
    base_orientation: Tuple[float, float, float, float] = key(
        "the hand frame's orientation (the palm's normal is its +y): a quaternion [x, y, z, w] "
        'or {axis, angle}', 'quaternion')
    palm_size: Tuple[float, float, float] = key(
        "the palm's full extents along the hand's x, y (its normal) and z", 'vector', unit='m',
        size=3, positive=True)
    segment_radius: float = key('the capsule radius of every finger segment', 'number',
                                unit='m', positive=True)
    segment_density: float = key('the density of the segments', 'number', unit='kg/m^3',
                                 positive=True)
    palm_mass: float = key("the palm's mass (the palm is fixed; for export)", 'number',
                           unit='kg', positive=True, default=0.1)
    # Fixed: the value; searched: the centre of the bounds, the bounds in base_yaw_bounds
    base_yaw: float = key(
        'a turn of the hand about the world vertical through the palm centre, after '
        'base_orientation: a number, or searched within {bounds: [lower, upper]} (beyond the '
        'paper)', 'custom', unit='rad', read='base_yaw', default=0.0,
        values='a number, {fixed: v} or {bounds: [lower, upper]}')
    # not keys: the searched ranges the reader finds at base_position and base_yaw (None:
    # fixed), each axis or the yaw a gene where its range is wider than a point
    base_position_bounds: Optional[Tuple[Bounds, Bounds, Bounds]] = None
    base_yaw_bounds: Optional[Bounds] = None

    @property
    def placement_searched(self):
        """Return whether the search places the palm (any base bounds of non-zero width)."""
        ranges = (self.base_position_bounds or ()) + (
            (self.base_yaw_bounds,) if self.base_yaw_bounds is not None else ())
        return any(bounds.width > 0 for bounds in ranges)


@dataclass(frozen=True)
class PositionGoal:
    """Object position `position` (world, m) wanted at `time` (s), measured along `axes`."""

    time: float = key('when the goal holds; strictly after the previous goal', 'number',
                      unit='s', positive=True)
    position: Tuple[float, float, float] = key('the wanted position of the object, world frame',
                                               'vector', unit='m', size=3)
    # also score interpolated goals from the previous goal (III.C)
    trajectory: bool = key('also score goals interpolated from the previous goal (III.C)',
                           'boolean')
    # the world axes eq. (3) measures, in x, y, z order
    axes: Tuple[str, ...] = key(
        'the world axes the distance measures, e.g. [x, y]: the plane of the table', 'custom',
        read='goal_axes', default=AXES, values='distinct axes of x, y, z')


@dataclass(frozen=True)
class OrientationGoal:
    """Object orientation `orientation` (quaternion x, y, z, w) wanted at `time` (s)."""

    time: float = key('when the goal holds; strictly after the previous goal', 'number',
                      unit='s', positive=True)
    orientation: Tuple[float, float, float, float] = key(
        'the wanted orientation: a quaternion [x, y, z, w] or {axis, angle}', 'quaternion')
    trajectory: bool = key('also score goals interpolated (slerp) from the previous goal',
                           'boolean')


@dataclass(frozen=True)
class SymmetrySpec:
    """The object looks the same turned by k * 2 pi / order about `axis` (object frame)."""

    axis: Tuple[float, float, float] = key("the axis of symmetry, in the object's own frame",
                                           'unit_vector')
    order: int = key('how many turns about it look the same (a cube: 4)', 'integer', minimum=2)


@dataclass(frozen=True)
class GoalSpec:
    """The position and orientation goals; goal 0 is the object's nominal start pose."""

    distance: str = key('the distance of position goals (eq. 3)', 'choice', choices=DISTANCES)
    position: Tuple[PositionGoal, ...] = key(
        'the position goals, in time order (may be []; at least one goal in all)', 'section',
        section=PositionGoal, listed=True, read='goal_list')
    orientation: Tuple[OrientationGoal, ...] = key(
        'the orientation goals, in time order (may be [])', 'section', section=OrientationGoal,
        listed=True, read='goal_list')
    samples_per_second: float = key("the spacing of a trajectory's interpolated goals",
                                    'number', unit='1/s', positive=True, default=10.0)
    # False: goals are absolute world poses. True: goals are given for the nominal start and
    # each world's goals move with its start (shifted by its position offset, turned by its
    # orientation delta), so randomizing the start never counts as an error by itself.
    relative_to_start: bool = key(
        "move each world's goals with its start (false: absolute world poses)", 'boolean',
        default=False)
    # None: every turn of the object counts (eq. 4). Otherwise orientation goals score the
    # nearest of the object's symmetric turns.
    orientation_symmetry: Optional[SymmetrySpec] = key(
        'the object looks the same turned about an axis: orientation goals score the nearest '
        'such turn (none: every turn counts, eq. 4)', 'section', section=SymmetrySpec,
        default=None)


@dataclass(frozen=True)
class RandomizationSpec:
    """Domain randomization ranges; each world draws every quantity uniformly."""

    position: Tuple[Bounds, Bounds, Bounds] = key(
        'the start position offset along world x, y and z: {x: [l, u], y: [l, u], z: [l, u]}',
        'custom', unit='m', read='axis_ranges', values='{x, y, z}, each [lower, upper]')
    orientation_axis: Tuple[float, float, float] = key(
        'the axis of the start orientation offset, world frame', 'unit_vector',
        yaml='orientation.axis')
    orientation: Bounds = key('the start orientation offset: an angle about that axis',
                              'bounds', unit='rad', angle=True, yaml='orientation.range')
    friction: Bounds = key("an offset added to the object's friction", 'bounds')
    scale: Bounds = key('a factor on every dimension of the object', 'bounds', positive=True)
    mass: Bounds = key("a factor on the object's mass", 'bounds', positive=True)

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

    initial_angle: ParameterSpec = key("each joint's angle at the start", 'parameter',
                                       unit='rad', per_joint=True, angle=True)
    finger_position_x: ParameterSpec = key("each finger's place on the palm along the hand's x",
                                           'parameter', unit='m')
    finger_position_z: ParameterSpec = key("each finger's place on the palm along the hand's z",
                                           'parameter', unit='m')
    segment_length: ParameterSpec = key(
        "each segment's length (per_finger_total: bounds for the whole finger)", 'parameter',
        unit='m', per_joint=True, total=True)
    axis_angle: ParameterSpec = key("each joint axis's angle in the palm's plane", 'parameter',
                                    unit='rad', per_joint=True, angle=True)
    joint_limits: ParameterSpec = key(
        "each joint's lower and upper limit (fixed: a pair [lower, upper]; none: no limits)",
        'custom', unit='rad', read='limits_setting',
        values='a setting as the others, or none')
    friction: ParameterSpec = key("the hand's friction coefficient", 'parameter', minimum=0)


@dataclass(frozen=True)
class PolicySpec:
    """The control policy and its bounds; fields of the other kind are None."""

    kind: str = key('the control policy: torques over time (III.B), or feed-forward PD (eq. 1)',
                    'choice', choices=POLICY_KINDS)
    duration: float = key('how long the policy acts; zero torque (plus gravity compensation) '
                          'afterwards', 'number', unit='s', positive=True)
    gravity_compensation: bool = key(
        'add the torques that hold the fingers against gravity', 'boolean',
        default=Depends('kind', (('torque', False), ('pd', True))),
        default_text='false for torque, true for pd')
    mode: Optional[str] = key(
        'constant: each of the knots holds over an equal interval; interpolated: linear '
        'between them', 'choice', choices=TORQUE_MODES,
        when=('kind', ('torque',), 'for a {} policy'), field_default=None)
    knots: Optional[int] = key('the torques K per joint', 'integer',
                               when=('kind', ('torque',), 'for a {} policy'), field_default=None)
    torque: Optional[ParameterSpec] = key(
        'the torques, per finger (applying to all its joints)', 'parameter', unit='N m',
        when=('kind', ('torque',), 'for a {} policy'), field_default=None)
    keyframe_times: Optional[Tuple[float, ...]] = key(
        'when each target holds, strictly increasing, within the duration', 'custom', unit='s',
        read='keyframes', values='a list of numbers > 0',
        when=('kind', ('pd',), 'for a {} policy'), field_default=None)
    target: Optional[ParameterSpec] = key(
        'the target joint angles of each keyframe, per finger', 'parameter', unit='rad',
        angle=True, when=('kind', ('pd',), 'for a {} policy'), field_default=None)
    kp: Optional[ParameterSpec] = key('the p coefficient, per finger', 'parameter',
                                      unit='N m/rad', minimum=0,
                                      when=('kind', ('pd',), 'for a {} policy'),
                                      field_default=None)
    kd: Optional[ParameterSpec] = key('the d coefficient, per finger', 'parameter',
                                      unit='N m s/rad', minimum=0,
                                      when=('kind', ('pd',), 'for a {} policy'),
                                      field_default=None)

    @property
    def num_knots(self):
        """Return the rows of ControllerDesign.values: K torques or keyframes."""
        return self.knots if self.kind == 'torque' else len(self.keyframe_times)


@dataclass(frozen=True)
class TorquePenaltySpec:
    """Equation (2): weight * (max |tau| - threshold) when max |tau| > threshold."""

    threshold: float = key('tau_p of eq. (2): the torque above which the penalty counts',
                           'number', unit='N m', minimum=0)
    weight: float = key('w of eq. (2)', 'number', positive=True, interval='(0, 1)',
                        noun='a weight w')


@dataclass(frozen=True)
class HorizonSpec:
    """The growing horizon of early_termination.horizon (hand_codesign.core.search.horizon)."""

    start: float = key('the first horizon', 'number', unit='s', positive=True, default=GIVEN,
                       default_text='one check interval')
    step: float = key('how much the horizon grows at a time', 'number', unit='s',
                      positive=True, default=GIVEN, default_text='one check interval')
    share: float = key('the share of a generation that must score at most the margins in '
                       'every objective before the horizon grows', 'number', positive=True,
                       interval='(0, 1]', noun='a share', default=0.5)


@dataclass(frozen=True)
class EarlyTerminationSpec:
    """Equation (6): stop a rollout when a goal misses by more than d_s or theta_s."""

    distance: float = key('d_s of eq. (6): stop a rollout whose position misses by more',
                          'number', unit='m', positive=True)
    angle: float = key('theta_s of eq. (6): stop a rollout whose orientation misses by more',
                       'number', unit='rad', positive=True, angle=True)
    checks_per_second: float = key('how often the margins are checked', 'number', unit='1/s',
                                   positive=True, default=10.0)
    horizon: Optional[HorizonSpec] = key(
        'sub-problems of growing horizon (core.search.horizon); none: whole rollouts',
        'section', section=HorizonSpec, default=None)


@dataclass(frozen=True)
class ContactSpec:
    """
    Ranges of the object's contact parameters, drawn per world (YAML `physics.contact`).

    Each range given is drawn uniformly by every world, from its own stream of the world's
    seed (core.sim.worlds), and applied to the object's contacts in each engine
    (core.sim.pybullet_sim, core.sim.mujoco_sim say how each maps). A range left out keeps
    the engine's own contact; stiffness and damping come as a pair, as both engines take them.
    """

    stiffness: Optional[Bounds] = key(
        "the normal stiffness of the object's contacts with the ground and the hand", 'custom',
        unit='N/m', read='contact_range', positive=True, default=None,
        values='[lower, upper], 0 < lower <= upper')
    damping: Optional[Bounds] = key(
        "the normal damping of the object's contacts (with stiffness)", 'custom',
        unit='N s/m', read='contact_range', minimum=0, default=None,
        values='[lower, upper], 0 <= lower <= upper')
    restitution: Optional[Bounds] = key(
        "the coefficient of restitution of the object's contacts with the ground", 'custom',
        read='contact_range', minimum=0, interval='[0, 1]', noun='coefficients', default=None,
        values='[lower, upper], 0 <= lower <= upper <= 1')

    def ranges(self):
        """Return (name, Bounds) of the ranges given, in CONTACT_PARAMETERS order."""
        return tuple((name, getattr(self, name)) for name in CONTACT_PARAMETERS
                     if getattr(self, name) is not None)


@dataclass(frozen=True)
class PhysicsSpec:
    """
    The physics engine and Bullet's settings; the defaults are those of Table I's runs.

    Fewer solver iterations and a shorter contact breaking threshold (Bullet keeps contact
    points up to that distance apart) make every step cheaper; bench/bench_physics.py measures
    how much faster and whether the ranking of designs and their robustness stay the same.
    """

    solver_iterations: int = key("Bullet's solver iterations per step", 'integer', default=50)
    contact_breaking_threshold: float = key(
        'how far apart Bullet keeps contact points', 'number', unit='m', positive=True,
        default=0.02)
    # 'pybullet' (Table I's runs) or 'mujoco' (core.sim.mujoco_sim, whose own contact settings
    # are fixed there; the two Bullet settings above do not apply to it). With `engines` it is
    # the list's first: the engine of what simulates one engine only (replay, export)
    engine: str = key('the physics engine (MuJoCo ignores the two Bullet settings)', 'choice',
                      choices=ENGINES, default='pybullet')
    # physics as a randomized quantity (issue 47): every candidate meets the same worlds in
    # each engine of the list (core.evaluate), scored by `engine_aggregate`
    engines: Tuple[str, ...] = key(
        'the physics engines every candidate is evaluated in, on the same worlds, e.g. '
        '[pybullet, mujoco] (instead of engine)', 'custom', read='engine_list', default=GIVEN,
        default_text='[engine]', values=f'distinct engines of {", ".join(ENGINES)}',
        field_default=())
    engine_aggregate: str = key(
        "with several engines: the mean of the engines' objectives, or per objective the "
        'worse engine', 'choice', choices=ENGINE_AGGREGATES, default='mean')
    # None: each engine's own contact (today's worlds, bit for bit). Here, not under
    # randomization: these are engine settings whose mapping and refusals depend on `engines`,
    # while randomization holds the object's seven quantities that Fig. 3's grid spans
    contact: Optional[ContactSpec] = key(
        "ranges of the object's contact parameters, drawn per world and applied in every "
        "engine (none: the engines' own contact)", 'section', section=ContactSpec,
        default=None, read='contact_section')

    def __post_init__(self):
        # one engine: the list of it. An `engine` that is not the list's first (code that sets
        # engine alone, as before the list: dataclasses.replace(physics, engine=...)) makes
        # the physics of that one engine.
        if len(self.engines) <= 1 or self.engine != self.engines[0]:
            object.__setattr__(self, 'engines', (self.engine,))

    def with_engines(self, engines):
        """Return a copy that evaluates in `engines` (a sequence of ENGINES), first one first."""
        engines = tuple(engines)
        return dataclasses.replace(self, engine=engines[0], engines=engines)


@dataclass(frozen=True)
class WeightsSpec:
    """Weights of the weighted-sum fitness: w_p for positions, w_r for orientations."""

    position: float = key('w_p: the weight of every position objective in the fitness',
                          'number', minimum=0, default=1.0)
    orientation: float = key('w_r: the weight of every orientation objective in the fitness',
                             'number', minimum=0, default=0.1)


@dataclass(frozen=True)
class RacingSpec:
    """
    Racing over the worlds (YAML `worlds.racing`, optional; not in the paper; off by default).

    A generation's candidates meet their worlds in `rounds` rounds of about equal shares; after
    each round a candidate stops once it can no longer be among the mu that CMA-ES selects,
    by a bound on what its remaining worlds can add (core.search.racing): each world's
    weighted objectives (the fitness of one world), less what the generation's candidates
    share on that world, are taken to lie in a band `range` wide, and the bound holds for
    every candidate and round at once with probability 1 - `delta`.
    """

    rounds: int = key("the rounds a generation's worlds are met in, of about equal shares",
                      'integer', minimum=2, default=4)
    # YAML `range` (a builtin's name as a field)
    value_range: float = key(
        "the width of the band a world's weighted objectives lie in, less what the "
        "generation's candidates share on that world", 'number', unit='m', positive=True,
        default=0.1, yaml='range')
    delta: float = key('the chance that any bound of a generation fails', 'number',
                       interval='(0, 1)', noun='a probability', default=0.05)


@dataclass(frozen=True)
class WorldsSpec:
    """
    How a candidate's worlds are scored and drawn (YAML `worlds`, optional; defaults: eq. 5).

    aggregate 'mean' is eq. (5), the mean over the worlds; 'worst' is the conditional value at
    risk of each objective: the mean over the worst `fraction` of the worlds
    (core.sim.objectives.combine_worlds). resample 'generation' evaluates each generation on a
    fresh draw of num_world_states worlds (core.sim.worlds, core.search.resampling); the run's
    result is then the best, on the run's fixed worlds, of the best designs of the last
    `final_check` generations.

    Whatever reads a candidate's objectives reads the aggregated ones: with 'worst' the
    hierarchy's thresholds judge its checks' worst worlds, and a horizon grows once a share
    of a generation tracks within the margins in its worst worlds, so later than on average.
    """

    aggregate: str = key('how the worlds score a candidate: the mean (eq. 5), or the mean of '
                         'its worst fraction of the worlds (CVaR)', 'choice',
                         choices=WORLD_AGGREGATES, default='mean')
    # of the worlds averaged with aggregate 'worst'; 1 with 'mean'
    fraction: float = key('the share of the worst worlds each objective averages', 'number',
                          interval='(0, 1]', noun='a fraction',
                          when=('aggregate', ('worst',), 'with aggregate: {}'),
                          field_default=1.0)
    resample: str = key('the worlds a candidate meets: one fixed set, or a fresh draw each '
                        'generation', 'choice', choices=WORLD_RESAMPLING, default='none')
    final_check: int = key(
        'the last generations whose best designs are checked on the fixed worlds; the best '
        "there is the run's result", 'integer', default=FINAL_CHECK,
        when=('resample', ('generation',), 'with resample: {}'))
    # None: every candidate meets every world (eq. 5)
    racing: Optional[RacingSpec] = key(
        "a generation's worlds met in rounds, a candidate stopped once it cannot be among the "
        'mu CMA-ES selects (core.search.racing; cma with aggregate: mean only; {}: the '
        'defaults)', 'section', section=RacingSpec, default=None)

    @property
    def worst_fraction(self):
        """Return the share of the worst worlds each objective averages (1.0: every world)."""
        return self.fraction if self.aggregate == 'worst' else 1.0


@dataclass(frozen=True)
class ArchiveSpec:
    """
    The archive of a quality-diversity search (YAML `optimizer.archive`, optional).

    Two descriptors (None: finger_length and joint_range, or initial_angle for joints without
    limits) span a grid of `cells`: of the design (core.task.descriptors) or of the outcome of its
    rollouts (core.outcomes: limit_rest, touch, shares of the worlds in [0, 1]); `ranges`
    (None: the least and greatest value each descriptor takes on the task's genome bounds,
    [0, 1] for an outcome) its extent.
    `emitters` (None: one per 10 candidates) share the population; `learning_rate` (None:
    0.01) is CMA-MAE's alpha.
    """

    descriptors: Optional[Tuple[str, ...]] = key(
        "the two descriptors the archive's grid spans: of the design (core.task.descriptors) "
        "or of its rollouts' outcome (core.outcomes)", 'custom', choices=ARCHIVE_DESCRIPTOR_NAMES,
        read='archive_descriptors', default=None,
        values='two different names of: ' + ', '.join(ARCHIVE_DESCRIPTOR_NAMES),
        default_text='finger_length, joint_range (initial_angle without joint limits)')
    cells: Tuple[int, ...] = key('the cells of the grid along each descriptor', 'custom',
                                 read='archive_cells', default=(10, 10),
                                 values='two whole numbers >= 1')
    ranges: Optional[Tuple[Tuple[float, float], ...]] = key(
        "the grid's extent along each descriptor: [[l0, u0], [l1, u1]]", 'custom',
        read='archive_ranges', default=None, values='two pairs [lower, upper], lower < upper',
        default_text="the least and greatest value on the genome's bounds ([0, 1] for an "
                     'outcome)')
    emitters: Optional[int] = key('the CMA-ES emitters sharing the population', 'integer',
                                  default=None, default_text='population // 10, at least 1')
    learning_rate: Optional[float] = key("CMA-MAE's alpha (cma-me: always 1)", 'number',
                                         interval='[0, 1]', default=None, default_text='0.01')


@dataclass(frozen=True)
class HierarchySpec:
    """The bottom-up search over hand structures of Fig. 1."""

    start: Tuple[int, ...] = key('the first structure: joints per finger, e.g. [1]',
                                 'structure')
    position_threshold: float = key(
        "stop at the structure whose best design's position errors are below this (and its "
        'orientation errors below orientation_threshold)', 'number', unit='m', minimum=0)
    orientation_threshold: float = key(
        "stop at the structure whose best design's orientation errors are below this (and its "
        'position errors below position_threshold)', 'number', unit='rad', minimum=0,
        angle=True)
    evaluation_world_states: int = key(
        'the held-out worlds the best design of each structure is checked on', 'integer')
    stop_structure: Optional[Tuple[int, ...]] = key('the last structure', 'structure',
                                                    default=None)
    max_fingers: Optional[int] = key('the most fingers a structure may have', 'integer',
                                     default=None)
    max_joints: Optional[int] = key('the most joints a finger may have', 'integer',
                                    default=None)


def resting_height(object_spec, scale=1.0, orientation=None):
    """
    Return the height of the object's centre above the plane when it rests on it.

    That is the object's extent below its centre along world z, for the object scaled by
    `scale` and turned to `orientation` (default: its nominal orientation).
    """
    rotation = rotation_matrix(object_spec.orientation if orientation is None
                               else orientation)
    vertical = np.abs(rotation[2])  # |z-components| of the object's local axes
    if object_spec.shape == 'sphere':
        return object_spec.radius * scale
    if object_spec.shape == 'box':
        return float(np.dot(vertical, np.array(object_spec.size) / 2)) * scale
    return (object_spec.radius + vertical[2] * object_spec.length / 2) * scale
