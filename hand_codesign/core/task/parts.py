"""
The parts of a Task, as the reader builds them: the task room's shared vocabulary.

Frozen dataclasses, the schema's constants and TaskError; the Task itself is in
hand_codesign.core.task.spec, and the schema is documented in hand_codesign.core.task. This
module imports nothing of the task room, so every other module of it (and the genome) can
import it.
"""

from dataclasses import dataclass
from typing import Any, Optional, Tuple

from hand_codesign.core.outcomes import OUTCOME_NAMES
from hand_codesign.core.rotations import rotation_matrix
import numpy as np

SHAPES = ('sphere', 'box', 'capsule')
STARTS = ('plane', 'midair')
DISTANCES = ('euclidean', 'manhattan')
ALGORITHMS = ('cma', 'mocma', 'ipop-cma', 'bipop-cma', 'cma-mae', 'cma-me')
RESTART_ALGORITHMS = ('ipop-cma', 'bipop-cma')  # CMA-ES with restarts (core.search.restarts)
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
    """Object position `position` (world, m) wanted at `time` (s), measured along `axes`."""

    time: float
    position: Tuple[float, float, float]
    trajectory: bool  # also score interpolated goals from the previous goal (III.C)
    axes: Tuple[str, ...] = AXES  # the world axes eq. (3) measures, in x, y, z order


@dataclass(frozen=True)
class OrientationGoal:
    """Object orientation `orientation` (quaternion x, y, z, w) wanted at `time` (s)."""

    time: float
    orientation: Tuple[float, float, float, float]
    trajectory: bool


@dataclass(frozen=True)
class SymmetrySpec:
    """The object looks the same turned by k * 2 pi / order about `axis` (object frame)."""

    axis: Tuple[float, float, float]  # unit vector in the object's own frame
    order: int  # >= 2: the number of turns (including none) that look the same


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
    # None: every turn of the object counts (eq. 4). Otherwise orientation goals score the
    # nearest of the object's symmetric turns.
    orientation_symmetry: Optional[SymmetrySpec] = None


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
class HorizonSpec:
    """The growing horizon of early_termination.horizon (hand_codesign.core.search.horizon)."""

    start: float  # s, the first horizon
    step: float  # s, how much it grows at a time
    share: float  # of a generation that must track within the margins before it grows


@dataclass(frozen=True)
class EarlyTerminationSpec:
    """Equation (6): stop a rollout when a goal misses by more than d_s or theta_s."""

    distance: float  # d_s, m
    angle: float  # theta_s, rad
    checks_per_second: float = 10.0
    horizon: Optional[HorizonSpec] = None  # sub-problems of growing horizon (horizon.py)


@dataclass(frozen=True)
class PhysicsSpec:
    """
    The physics engine and Bullet's settings; the defaults are those of Table I's runs.

    Fewer solver iterations and a shorter contact breaking threshold (Bullet keeps contact
    points up to that distance apart) make every step cheaper; bench/bench_physics.py measures
    how much faster and whether the ranking of designs and their robustness stay the same.
    """

    solver_iterations: int = 50
    contact_breaking_threshold: float = 0.02  # m
    # 'pybullet' (Table I's runs) or 'mujoco' (core.sim.mujoco_sim, whose own contact settings
    # are fixed there; the two Bullet settings above do not apply to it)
    engine: str = 'pybullet'


@dataclass(frozen=True)
class WeightsSpec:
    """Weights of the weighted-sum fitness: w_p for positions, w_r for orientations."""

    position: float = 1.0
    orientation: float = 0.1


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

    rounds: int = 4
    value_range: float = 0.1  # YAML `range`: width of a world's weighted objectives (m)
    delta: float = 0.05  # chance that any bound of a generation fails


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

    aggregate: str = 'mean'
    fraction: float = 1.0  # of the worlds averaged with aggregate 'worst'; 1 with 'mean'
    resample: str = 'none'
    final_check: int = FINAL_CHECK
    racing: Optional[RacingSpec] = None  # None: every candidate meets every world (eq. 5)

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

    descriptors: Optional[Tuple[str, ...]] = None
    cells: Tuple[int, ...] = (10, 10)
    ranges: Optional[Tuple[Tuple[float, float], ...]] = None
    emitters: Optional[int] = None
    learning_rate: Optional[float] = None


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
