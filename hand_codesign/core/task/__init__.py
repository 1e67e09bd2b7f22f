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
      orientation_symmetry: {axis: [0, 0, 1], order: 4}   # optional, see below
      position:                      # goals i = 1..n, strictly increasing times (may be [])
        - {time: 1.5, position: [0.01, 0, 0.02], axes: [x, y], trajectory: false}
      orientation:                   # goals i = 1..m (may be []); at least one goal in all
        - {time: 1.5, orientation: {axis: [0, 0, 1], angle: 0.785}, trajectory: true}
    randomization:                   # domain randomization, uniform in each range
      position: {x: [-0.005, 0.005], y: [-0.005, 0.005], z: [0, 0]}   # delta, m, world axes
      orientation: {axis: [0, 0, 1], range: [-0.4, 0.4]}             # delta angle, rad
      friction: [-0.1, 0.1]          # delta added to object.friction
      scale: [0.66, 1.5]             # factor on every object dimension
      mass: [0.66, 1.5]              # factor on object.mass
    world_states: 8                  # randomized worlds per candidate (old name: num_world_states)
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
      # horizon: {start: 0.1, step: 0.1, share: 0.5}    # optional: sub-problems of growing
      #   horizon (hand_codesign.core.search.horizon): the first horizon (s, default one check
      #   interval), how much it grows (s, default one check interval) once `share` (0 to 1,
      #   default 0.5) of a generation scores at most the margins' score in every objective
    weights: {position: 1.0, orientation: 0.1}          # optional: w_p, w_r of the fitness
    physics: {solver_iterations: 50, contact_breaking_threshold: 0.02}   # optional: Bullet's
                                     # settings; these defaults reproduce the paper's runs
    worlds: {aggregate: worst, fraction: 0.25, resample: generation, final_check: 5}
                                     # optional; default {aggregate: mean, resample: none}, eq. 5
                                     # on one fixed set of worlds. See below.
    optimizer:
      algorithm: cma                 # cma (weighted sum) | mocma (Pareto front) | ipop-cma |
                                     # bipop-cma (CMA-ES with restarts, core.search.restarts; the
                                     # budget stays iterations x population evaluations) |
                                     # cma-mae | cma-me (quality diversity: an archive of
                                     # designs, core.search.quality_diversity)
      iterations: 100                # generations (per hand structure)
      population: 80
      initial_sigma: 0.1             # optional, in the normalized genome space
      restart_stagnation: 20         # optional, ipop-cma / bipop-cma only: generations
                                     # without improvement that end a CMA-ES instance
      archive:                       # optional, cma-mae / cma-me only (these defaults):
        descriptors: [finger_length, joint_range]  # two of core.task.descriptors' descriptors;
                                     # default these, or initial_angle for joints without limits
                                     # or of core.outcomes' (limit_rest, touch: shares of the
                                     # worlds, measured in the rollouts, each in [0, 1])
        cells: [10, 10]              # of the grid, along each descriptor
        ranges: [[0.16, 0.36], [0, pi]]            # optional; default: the least and
                                     # greatest value on the task's genome bounds ([0, 1] for
                                     # an outcome)
        emitters: 4                  # optional; default population // 10, at least 1
        learning_rate: 0.01          # optional: CMA-MAE's alpha (cma-me: always 1)
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
    two_stage: true                  # optional: stage 1 on the nominal world only, then stage 2
                                     # on the randomized worlds from stage 1's result (Tasks 1/2)

A position goal's `axes` (optional, default [x, y, z]) names the world axes its distance
measures: [x, y] scores an object on the plane by where it is on the plane, whatever height its
randomized scale rests it at. `orientation_symmetry` says the object looks the same turned by
any multiple of 360 / order degrees about `axis` of its own frame (a cube: order 4 about each
face normal): orientation goals then score the nearest of those turns (eq. 4 taken modulo the
symmetry). Without it every turn counts, as in the paper.

`worlds` decides how the worlds score a candidate and which worlds it meets:

- `aggregate: mean` (default) averages each objective over the worlds, eq. (5);
  `aggregate: worst` with `fraction: f` in (0, 1] averages it over the worst f of the worlds
  only, its conditional value at risk (core.sim.objectives.combine_worlds), so the search favours
  designs that hold up in their bad worlds rather than on average.
- `resample: none` (default) evaluates every candidate on the same `world_states` worlds
  of the seed; `resample: generation` draws fresh worlds for each generation (another stream of
  the seed, core.sim.worlds), so the design cannot fit one set of worlds. The run then reports the
  best, re-evaluated on the fixed worlds, of the best designs of the last `final_check`
  (default 5) generations (core.search.resampling). Not with a hierarchy, two stages or a horizon.

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

# The task room: its parts (parts), the Task (spec), its reader (reader, built on values,
# settings_reader and design_reader), its cross-field rules (checks), the genome a task's
# bounds define (genome), the descriptors of a design on them (descriptors) and the Variant
# of a task a candidate is evaluated on (variant). This face is the import path users know;
# the room's modules import each other by their own paths, never through this face, so loading
# it cannot run in a circle. The room imports only core's root modules (design, rotations,
# outcomes) besides its own.
from hand_codesign.core.rotations import axis_angle_quaternion
from hand_codesign.core.task.parts import (ALGORITHMS, ArchiveSpec, AXES, Bounds, DISTANCES,
                                           EarlyTerminationSpec, GoalSpec, HandSpec, HierarchySpec,
                                           HorizonSpec, MORPHOLOGY_PARAMETERS, MorphologySpec,
                                           ObjectSpec, OrientationGoal, PARAMETER_MODES,
                                           ParameterSpec, PhysicsSpec, POLICY_KINDS, PolicySpec,
                                           PositionGoal, RandomizationSpec, resting_height,
                                           RESTING_TOLERANCE, SHAPES, STARTS, SymmetrySpec,
                                           TaskError, TORQUE_MODES, TorquePenaltySpec, WeightsSpec,
                                           WORLD_AGGREGATES, WORLD_RESAMPLING, WorldsSpec)
from hand_codesign.core.task.reader import load_task, parse_design, parse_task
from hand_codesign.core.task.spec import Task

__all__ = [
    'ALGORITHMS', 'ArchiveSpec', 'AXES', 'axis_angle_quaternion', 'Bounds', 'DISTANCES',
    'EarlyTerminationSpec', 'GoalSpec', 'HandSpec', 'HierarchySpec', 'HorizonSpec', 'load_task',
    'MORPHOLOGY_PARAMETERS', 'MorphologySpec', 'ObjectSpec', 'OrientationGoal', 'PARAMETER_MODES',
    'ParameterSpec', 'parse_design', 'parse_task', 'PhysicsSpec', 'POLICY_KINDS', 'PolicySpec',
    'PositionGoal', 'RandomizationSpec', 'resting_height', 'RESTING_TOLERANCE', 'SHAPES', 'STARTS',
    'SymmetrySpec', 'Task', 'TaskError', 'TORQUE_MODES', 'TorquePenaltySpec', 'WeightsSpec',
    'WORLD_AGGREGATES', 'WORLD_RESAMPLING', 'WorldsSpec',
]
