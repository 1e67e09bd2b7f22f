"""
The MuJoCo world of a candidate: the second physics engine, beside PyBullet's.

Same interface and semantics as core.sim.pybullet_sim.Simulator (`build`, `object_shape`,
`start_collisions`, `rollout` returning a core.sim.events.Rollout, the same EventPlan of checks,
watches and frames), so core.evaluate runs either engine from the task's
`physics: {engine: mujoco}`. The model is built in code with mujoco.MjSpec from the very
HandModel table that core.sim.hand builds in PyBullet: a ground plane, the palm welded to the world
at the hand's base pose, one body per segment with its hinge, capsule, mass and inertia (about
its centre, link axes, given explicitly), and one free object body whose shape, size, mass,
inertia, friction and pose are written into the candidate's compiled model for each world
(`_load_world`: the same fields as a model compiled per world, bit for bit, without the
1.5 ms compile), and every world starts from a reset data, so rollouts do not depend on the
order of the worlds.

Settings chosen to match Bullet on this model (one place; measured in test_mujoco_sim.py):
- Joint ranges are radians (`compiler.degree` off: MjSpec reads degrees by default); equal
  limits (a locked joint, which Bullet accepts) become a range of LOCKED_RANGE.
- The palm is a box given as a convex mesh: MuJoCo's analytic capsule-box test missed a
  segment piercing the thin palm (Bullet: 2.8 cm deep; MuJoCo's box: no contact, 3.7 mm
  apart), the general convex test finds it.
- The palm is welded to the world, and MuJoCo's parent filter does not apply to bodies welded
  to the world: palm and every finger's first segment are excluded explicitly (Bullet does not
  collide a link with its parent). Non-adjacent links collide, as with Bullet's
  URDF_USE_SELF_COLLISION.
- Friction: Bullet multiplies the two coefficients, MuJoCo takes the larger unless one geom
  has a higher `priority`, whose coefficient then wins. Ground 1 (priority 0), hand f_h
  (priority 1: hand-ground f_h, Bullet's f_h * 1), object f_h * f_o (priority 2: hand-object
  f_h * f_o as in Bullet), and an explicit object-ground pair with f_o. Left different:
  segment-segment contacts use f_h where Bullet uses f_h^2 (fingers rarely touch each other).
  Sliding friction only (condim 3), as Bullet has no rolling or spinning friction here. The
  friction cone is elliptic, not MuJoCo's default pyramid: over 200 designs of a Task 5 search
  it ranks the box's position (Spearman 0.848 against 0.785) and Task 6's turn (0.875 against
  0.795) more as Bullet does (bench/bench_engine_softness.py, docs/results/engine-softness.md).
- Contacts and limits are made stiff: MuJoCo's default softness (solref 0.02 s) lets a box
  sink by millimetres and a joint pass its limit by tens of mrad, while Bullet's constraints
  are hard. CONTACT_SOLREF / LIMIT_SOLREF use the stiffest time constant MuJoCo accepts
  (twice the time step) with critical damping, and SOLIMP an impedance near 1.
- Margins (MuJoCo 4: a contact or limit acts within `margin`, is only detected within
  `margin + gap`): the object's contacts with the hand are read within TOUCH_MARGIN and act
  only when they touch; the object-ground contact and the joint limits act from RESTING_MARGIN
  off, so that a box on the ground and a joint on its limit are held from the first step.
  Left different, MuJoCo's own: its convex contacts lift a sliding box (0.85 mm at 0.4 m/s,
  none in Bullet; docs/results/engines/README.md).
- Gravity compensation (a torque policy's or eq. (1)'s N(theta)): `gravcomp` 1 on every
  segment, which MuJoCo applies as the passive joint forces that cancel gravity, exactly
  N(theta), without Python in the step loop.
- Integrator: MuJoCo's semi-implicit Euler, as Bullet's. Not modelled: Bullet's default
  multibody damping (0.04 of the link velocity), small at these speeds.

The rollout loop is PyBullet's (core.sim.events.play), with one difference in how the steps
between its events are taken: an open-loop torque policy's torques are known in advance, so
MuJoCo steps in C (mj_step's nstep) from one torque change or event to the next, with no
Python per step (test_mujoco_sim checks it is bit for bit the single steps). A PD policy's
law, eq. (1), is stepped in C as well (core.sim.mujoco_native: mj_step1, the law from
MuJoCo's inverse dynamics, mj_step2), bit for bit the law in Python (`mujoco_torques`, which
steps it where no C compiler is at hand; test_mujoco_native).

Unstable simulation: besides the object and joint checks of PyBullet's simulator, MuJoCo resets a
diverging state by itself and counts a warning; a rollout with such a warning is unstable.
"""

import math
from typing import Callable, Optional

from hand_codesign.core.outcomes import CONTACT_DISTANCE
from hand_codesign.core.sim import mujoco_native
from hand_codesign.core.sim.events import EventPlans, joints_intact, object_intact, play
from hand_codesign.core.sim.hand import HandModel
from hand_codesign.core.sim.policies import TorquePolicy
from hand_codesign.core.sim.scene import COLLISION_TOLERANCE, GRAVITY, GROUND_FRICTION
import mujoco
import numpy as np

MUJOCO_VERSION = mujoco.__version__
# m: contacts of the object are detected this far apart but act only when they penetrate, so
# core.outcomes can read touches without changing the physics. MuJoCo 4 activates a contact
# within `margin` and only detects it within `margin + gap` (includemargin = margin): the object
# has margin 0 and gap TOUCH_MARGIN. (margin = gap = TOUCH_MARGIN, the rule of older MuJoCo,
# made every hand-object contact act from 1 mm apart and hold the hand 1 mm off the object.)
TOUCH_MARGIN = CONTACT_DISTANCE
# m or rad: the object-ground contact and the joint limits act from this far off, not only once
# passed: a box starting on the ground and a joint starting on its limit are held from the first
# step, as by Bullet's constraints (with margin 0 MuJoCo lets the box fall freely for one step,
# 0.25 mm, and a joint pushed onto its limit pass it by tens of mrad); they rest this far off
RESTING_MARGIN = 1e-6
GROUND_SIZE = 50.0  # m, half extent of the ground plane (only drawn; a plane is infinite)
CONTACT_SOLIMP = (0.99, 0.999, 0.001, 0.5, 2.0)
LIMIT_SOLIMP = (0.9999, 0.9999, 0.001, 0.5, 2.0)
SOLREF_DAMPING_RATIO = 1.0  # critical damping: nothing bounces, as in Bullet
HAND_PRIORITY, OBJECT_PRIORITY = 1, 2
# rad: the range of a joint whose limits coincide (Bullet locks it there; MuJoCo wants
# lower < upper)
LOCKED_RANGE = 1e-9
# bytes of MjData's arena (contacts, constraints, the solver's stack): these scenes use about
# 20 kB (a few contacts, under 30 constraint rows); MuJoCo's default, 14 MB, costs about 1 ms
# to allocate and clear at each compile. The size changes no result, only what fits.
ARENA_BYTES = 2 << 20
_DIVERGENCE_WARNINGS = tuple(int(kind) for kind in (
    mujoco.mjtWarning.mjWARN_BADQACC, mujoco.mjtWarning.mjWARN_BADQPOS,
    mujoco.mjtWarning.mjWARN_BADQVEL))


def stiff_solref(time_step):
    """Return the stiffest (time constant, damping ratio) MuJoCo accepts at `time_step`."""
    return (2.0 * time_step, SOLREF_DAMPING_RATIO)


def contact_solref(contact, mass, time_step):
    """
    Return the solref of the object's geom and of its ground pair for a world's contact.

    Args:
        contact: the world's core.sim.worlds.ContactState, or None (the stiff default).
        mass: the world's object mass (kg).
        time_step: the task's time step (s).

    Returns:
        (geom solref, pair solref): the geom's sets the object's contacts with the hand (its
        priority wins over the hand's), the pair's those with the ground.

    Why these maps (the differences are genuine modelling choices of the engines):
    - stiffness K (N/m), damping D (N s/m): MuJoCo's direct solref (-k, -b) is a reference
      acceleration per metre and per m/s, so k = K / m and b = D / m with the object's mass:
      against the immovable ground that is the spring-damper's own frequency sqrt(K / m) and
      damping ratio D / (2 sqrt(K m)). Against a finger the effective mass is smaller. Unlike
      Bullet's spring per contact point, MuJoCo's acts on the constraint as a whole (four
      corners are not four times as stiff), and its impedance (SOLIMP near 1) lets the spring
      carry only (1 - d) / d of a steady load: an object sinks far less at rest than in
      Bullet, while its impact rings alike.
    - restitution e: MuJoCo has none apart from the contact's damping, so e sets the damping
      ratio z of a damped oscillator whose bounce is e, z = -ln e / sqrt(pi^2 + ln^2 e), at
      the stiffness of the default contact (a time constant of two steps); the bounce ends
      once the constraint stops pushing, a little before the spring is back at rest, so it is
      a little lower than e, and there is no velocity threshold as in Bullet. Only the ground
      pair bounces, as in Bullet (core.sim.pybullet_sim.Simulator._set_contact).
    """
    stiff = stiff_solref(time_step)
    if contact is None:
        return stiff, stiff
    if contact.stiffness is not None:
        if contact.restitution is not None:
            raise ValueError('physics.contact: MuJoCo takes a damping or a restitution, not both '
                             '(its restitution is the damping)')
        direct = (-contact.stiffness / mass, -contact.damping / mass)
        return direct, direct
    if contact.restitution is None:
        return stiff, stiff
    return stiff, bouncing_solref(contact.restitution, time_step)


def bouncing_solref(restitution, time_step):
    """Return the direct solref whose damping ratio bounces by `restitution` (see above)."""
    stiffness = 1.0 / (2.0 * time_step) ** 2  # the default contact's (stiff_solref)
    if restitution <= 0.0:
        ratio = 1.0
    else:
        log = math.log(restitution)
        ratio = -log / math.sqrt(math.pi ** 2 + log ** 2)
    return (-stiffness, -2.0 * ratio * math.sqrt(stiffness))


def object_inertia(shape, size, mass):
    """
    Return the diagonal inertia (kg m^2) of the object about its centre, as Bullet has it.

    Box and sphere: the solid's; capsule: Bullet's approximation, the box bounding it.
    """
    if shape == 'box':
        x, y, z = size
        return (mass * (y * y + z * z) / 12, mass * (x * x + z * z) / 12,
                mass * (x * x + y * y) / 12)
    if shape == 'sphere':
        return (0.4 * mass * size[0] ** 2,) * 3
    radius, length = size
    across, along = 2 * radius, 2 * radius + length
    return (mass * (across ** 2 + along ** 2) / 12,) * 2 + (mass * 2 * across ** 2 / 12,)


def _geom_size(shape, size):
    """Return (MuJoCo geom size, bounding radius, aabb half extents) of an object size."""
    if shape == 'box':
        half = tuple(s / 2 for s in size)
        return half, math.sqrt(sum(h * h for h in half)), half
    if shape == 'sphere':
        return (size[0], 0.0, 0.0), size[0], (size[0],) * 3
    radius, length = size
    return ((radius, length / 2, 0.0), radius + length / 2,
            (radius, radius, radius + length / 2))


_GEOM_TYPES = {'box': mujoco.mjtGeom.mjGEOM_BOX, 'sphere': mujoco.mjtGeom.mjGEOM_SPHERE,
               'capsule': mujoco.mjtGeom.mjGEOM_CAPSULE}


def _sequential_mean(values):
    total = 0.0
    for value in values.tolist():
        total += value
    return total / len(values)


_SIZE_NAMES = []  # MjModel's size attributes (nq, nv, ..., narena), read on first use


def model_sizes(m):
    """Return the sizes of a compiled model (nq, nv, nbody, ..., narena): what MjData holds."""
    if not _SIZE_NAMES:
        _SIZE_NAMES.extend(name for name in dir(m)
                           if name.startswith('n') and isinstance(getattr(m, name), int))
    return tuple(getattr(m, name) for name in _SIZE_NAMES)


def _wxyz(quaternion):
    x, y, z, w = quaternion
    return [w, x, y, z]


def hand_spec(model: HandModel, time_step, base_position=(0.0, 0.0, 0.0),
              base_orientation=(0.0, 0.0, 0.0, 1.0), object_shape='box',
              gravity_compensation=False):
    """
    Return the MjSpec of ground, hand and object (its size set per world later).

    `base_orientation` is x, y, z, w as everywhere in this package (MuJoCo's order is w first).
    Segments are bodies `<link name>` with hinges `<joint name>`; the object is body `object`
    (none with object_shape=None).
    """
    spec = mujoco.MjSpec()
    spec.modelname = 'hand'
    spec.compiler.degree = False
    spec.option.timestep = time_step
    spec.option.gravity = [0.0, 0.0, GRAVITY]
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    solref = stiff_solref(time_step)
    world = spec.worldbody
    world.add_geom(name='ground', type=mujoco.mjtGeom.mjGEOM_PLANE,
                   size=[GROUND_SIZE, GROUND_SIZE, 1.0], friction=[GROUND_FRICTION, 0, 0],
                   condim=3, solref=solref, solimp=CONTACT_SOLIMP)
    palm = world.add_body(name='palm', pos=list(base_position),
                          quat=_wxyz(base_orientation))
    sx, sy, sz = model.palm_size
    palm.mass = model.palm_mass
    palm.inertia = [model.palm_mass * (sy * sy + sz * sz) / 12,
                    model.palm_mass * (sx * sx + sz * sz) / 12,
                    model.palm_mass * (sx * sx + sy * sy) / 12]
    palm.explicitinertial = True
    hand_geom = {'friction': [model.friction, 0, 0], 'condim': 3,
                 'priority': HAND_PRIORITY, 'solref': solref, 'solimp': CONTACT_SOLIMP}
    corners = [[x * sx / 2, y * sy / 2, z * sz / 2]
               for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    spec.add_mesh(name='palm', uservert=[value for corner in corners for value in corner])
    palm.add_geom(name='palm', type=mujoco.mjtGeom.mjGEOM_MESH, meshname='palm', **hand_geom)
    bodies = []
    for link in model.links:
        parent = palm if link.parent < 0 else bodies[link.parent]
        body = parent.add_body(name=link.name, pos=list(link.joint_position))
        body.mass = link.mass
        body.ipos = list(link.centre)
        body.inertia = list(link.inertia)
        body.explicitinertial = True
        body.gravcomp = 1.0 if gravity_compensation else 0.0
        joint = {'name': link.joint_name, 'type': mujoco.mjtJoint.mjJNT_HINGE,
                 'axis': list(link.joint_axis)}
        if link.lower_limit is not None:
            upper = max(link.upper_limit, link.lower_limit + LOCKED_RANGE)
            joint.update(range=[link.lower_limit, upper],
                         limited=mujoco.mjtLimited.mjLIMITED_TRUE,
                         solref_limit=solref, solimp_limit=LIMIT_SOLIMP, margin=RESTING_MARGIN)
        body.add_joint(**joint)
        if link.cylinder_height > 0:
            body.add_geom(name=link.name, type=mujoco.mjtGeom.mjGEOM_CAPSULE,
                          size=[link.radius, 0, 0],
                          fromto=[0, link.radius, 0, 0, link.length - link.radius, 0],
                          **hand_geom)
        else:
            body.add_geom(name=link.name, type=mujoco.mjtGeom.mjGEOM_SPHERE,
                          size=[link.radius, 0, 0], pos=list(link.centre), **hand_geom)
        if link.parent < 0:
            spec.add_exclude(bodyname1='palm', bodyname2=link.name)
        bodies.append(body)
    if object_shape is None:
        return spec
    thing = world.add_body(name='object', pos=[0.0, 0.0, 1.0])
    thing.add_freejoint(name='object')
    thing.mass = 1.0
    thing.inertia = [1.0, 1.0, 1.0]
    # the centre of mass at the shape's centre, its axes the shape's: an unset ipos makes the
    # compiler copy the body's position into it, which put a box's centre of mass on its top face
    thing.ipos = [0.0, 0.0, 0.0]
    thing.iquat = [1.0, 0.0, 0.0, 0.0]
    thing.explicitinertial = True
    thing.add_geom(name='object', type=_GEOM_TYPES[object_shape], size=[0.01, 0.01, 0.01],
                   friction=[1.0, 0, 0], condim=3, priority=OBJECT_PRIORITY, solref=solref,
                   solimp=CONTACT_SOLIMP, margin=0.0, gap=TOUCH_MARGIN)
    spec.add_pair(name='object_ground', geomname1='object', geomname2='ground', condim=3,
                  friction=[1.0, 1.0, 0.0, 0.0, 0.0], solref=solref, solimp=CONTACT_SOLIMP,
                  margin=RESTING_MARGIN)
    return spec


def model_mjcf(model: HandModel, time_step, base_position=(0.0, 0.0, 0.0),
               base_orientation=(0.0, 0.0, 0.0, 1.0), gravity_compensation=False, name='hand'):
    """
    Return the MJCF text (hand.xml) of a hand model on the ground, as the simulator builds it.

    Its keyframe `initial` holds the initial joint angles (MJCF, like URDF, starts every joint
    at 0 otherwise): `mj_resetDataKeyframe(model, data, 0)` starts the hand as simulated.
    """
    spec = hand_spec(model, time_step, base_position, base_orientation, None,
                     gravity_compensation)
    spec.modelname = name
    spec.add_key(name='initial', qpos=list(model.initial_angles))
    spec.compile()
    return spec.to_xml()


class _DataViews:
    """
    Arrays of an MjData that the rollout loop reads at every event, looked up once.

    Each is a view into the MjData's memory, so it stays current as the data steps; reading
    `data.qpos` or `data.warning.number` instead makes a new array each time (about 2 us of
    an event's 10 in the rollout loop).
    """

    def __init__(self, data):
        self.qpos, self.qvel = data.qpos, data.qvel
        self.warnings = data.warning.number  # counts by mjtWarning


class MujocoSimulator(EventPlans):
    """A compiled MuJoCo model of one candidate, its data and the rollout loop."""

    engine = 'mujoco'
    chunked = True  # step open-loop torques in C between changes and events (False: one by one)
    native = True  # step a PD policy's law in C (core.sim.mujoco_native) when it can be built

    def __init__(self):
        """Start without a model: `build` compiles one per candidate."""
        self.client = self  # evaluate() checks a simulator's client to know it is open
        self.task = None
        self.model = None  # the HandModel
        self.mj_model = self.mj_data = None
        self._data_sizes = self._scratch = None  # the sizes of the model mj_data was made for
        self._views = None  # _DataViews of mj_data
        self.object_body = None  # not None while a world's object is in the scene
        EventPlans.__init__(self)

    def close(self):
        """Drop the compiled model."""
        self.client = None
        self.mj_model = self.mj_data = self._data_sizes = self._scratch = self._views = None

    def __enter__(self):
        """Return the simulator, closed at the end of the with block."""
        return self

    def __exit__(self, *exc_info):
        """Close the simulator."""
        self.close()

    # ---------------------------------------------------------------- scene

    def build(self, task, model: HandModel):
        """Compile ground, hand and object of one candidate on `task`."""
        spec = hand_spec(model, task.time_step, model.base_position,
                         model.base_orientation, task.object_spec.shape,
                         task.policy.gravity_compensation)
        spec.memory = ARENA_BYTES
        self.mj_model = spec.compile()
        # a candidate of the same sizes as the last one (the same structure) reuses its data:
        # making an MjData (a 14 MB arena) costs about 1 ms, and every rollout starts from
        # mj_resetData, which clears it completely
        sizes = model_sizes(self.mj_model)
        if sizes != self._data_sizes:
            self.mj_data = mujoco.MjData(self.mj_model)
            self._scratch = None  # the PD law's MjData, made on first use
            self._data_sizes = sizes
            self._views = _DataViews(self.mj_data)
        self._hold_rows = self._hold_until = self._native_law = None
        self.task, self.model = task, model
        self._joints = model.num_joints
        self._object_body = self.mj_model.body('object').id
        self._palm_body = self.mj_model.body('palm').id
        self._object_geom = self.mj_model.geom('object').id
        self._object_pair = self.mj_model.pair('object_ground').id
        self._object_qpos = self.mj_model.jnt_qposadr[self.mj_model.joint('object').id]
        self._ground_geom = self.mj_model.geom('ground').id
        self._hand_geoms = frozenset(
            index for index in range(self.mj_model.ngeom)
            if index not in (self._ground_geom, self._object_geom))
        self._loaded = None

    def object_shape(self, state, shape):
        """Return what `rollout` needs of a world's object besides its state: its shape."""
        return shape

    def _load_world(self, state, shape):
        """
        Write a world's object (size, mass, inertia, friction, start pose) into the model.

        The candidate's model is compiled once (`build`); a world's differences are written
        into its fields, then mj_setConst recomputes what depends on them (subtree masses,
        dof_M0, the invweights that scale the contact impedance, dof_length, the object's
        bounding volume). The fields are the compiler's for that world bit for bit, the
        object's inertial frame included (test_mujoco_sim compares every array with a model
        compiled for the world), so the physics and its bits are those of a model compiled
        per world, without the compile (about 1.5 ms a world).
        """
        key = (state, shape)
        if self._loaded == key:
            return
        m, d = self.mj_model, self.mj_data
        size, bound, half = _geom_size(shape, state.size)
        geom, body = self._object_geom, self._object_body
        m.geom_size[geom] = size
        m.geom_rbound[geom] = bound
        m.geom_aabb[geom] = (0.0, 0.0, 0.0, *half)
        m.geom_friction[geom, 0] = self.model.friction * state.friction
        m.pair_friction[self._object_pair] = (state.friction, state.friction, 0.0, 0.0, 0.0)
        m.body_mass[body] = state.mass
        m.geom_solref[geom], m.pair_solref[self._object_pair] = contact_solref(
            state.contact, state.mass, self.task.time_step)
        m.body_inertia[body] = object_inertia(shape, state.size, state.mass)
        orientation = _wxyz(state.orientation)
        m.body_pos[body] = state.position
        m.body_quat[body] = orientation
        start = self._object_qpos
        for pose in (m.qpos0, m.qpos_spring):
            pose[start:start + 3] = state.position
            pose[start + 3:start + 7] = orientation
        mujoco.mj_setConst(m, d)
        # the compiler's means (in its order of summation); meaninertia scales the solver's
        # tolerance. Left as built: stat.meansize, which only scales drawings.
        m.stat.meaninertia = _sequential_mean(m.dof_M0)
        m.stat.meanmass = _sequential_mean(m.body_mass[1:])
        self._loaded = key

    def reset(self, state, shape):
        """Load a world and put hand and object at their start, at rest (a fresh state)."""
        self._load_world(state, shape)
        self._start(self.mj_model, self.mj_data, state)

    def _start(self, m, d, state):
        mujoco.mj_resetData(m, d)
        d.qpos[:self._joints] = self.model.initial_angles
        start = self._object_qpos
        d.qpos[start:start + 3] = state.position
        d.qpos[start + 3:start + 7] = _wxyz(state.orientation)

    def _place_geometry(self, state, shape):
        """Write a world's object geometry and pose into the model, for collisions only."""
        m, d = self.mj_model, self.mj_data
        self._loaded = None  # the world loaded for rollouts is no longer whole
        size, bound, half = _geom_size(shape, state.size)
        geom = self._object_geom
        m.geom_size[geom] = size
        m.geom_rbound[geom] = bound
        m.geom_aabb[geom] = (0.0, 0.0, 0.0, *half)
        self._start(m, d, state)
        mujoco.mj_kinematics(m, d)
        mujoco.mj_collision(m, d)
        return d

    def start_collisions(self, objects):
        """
        Return True if the hand starts in contact with itself, the ground or any object.

        `objects` is a list of (ObjectState, shape) of the worlds; a contact counts when it
        penetrates deeper than COLLISION_TOLERANCE, as in core.sim.
        """
        hand = self._hand_geoms
        for state, shape in objects:
            d = self._place_geometry(state, shape)
            count = d.ncon
            if not count:
                continue
            contacts = d.contact  # read as arrays: a contact object each costs more
            deep = ~(contacts.dist[:count] >= -COLLISION_TOLERANCE)
            if any(geom in hand for geom in contacts.geom[:count][deep].ravel().tolist()):
                return True
        return False

    # ---------------------------------------------------------------- rollout

    def rollout(self, state, shape, policy, schedule,
                on_frame: Optional[Callable] = None, frame_every=1,
                on_end: Optional[Callable] = None):
        """
        Run one world from its start: return a core.sim.events.Rollout.

        `on_frame(step, simulator)` and `on_end(simulator, rollout)` as in PyBullet's
        (core.sim.pybullet_sim.Simulator.rollout); here the simulator's `mj_model` and
        `mj_data` hold the scene.
        """
        self.reset(state, shape)
        plan = self.plan(schedule, frame_every if on_frame is not None else 0)
        trace = schedule.new_trace(state)
        self.object_body = self._object_body
        try:
            result = self._run(policy, plan, trace, state, on_frame)
            if on_end is not None:
                on_end(self, result)
            return result
        finally:
            self.object_body = None

    def object_pose(self):
        """Return the object's (position, orientation x, y, z, w) as tuples of floats."""
        start = self._object_qpos
        x, y, z, qw, qx, qy, qz = self._views.qpos[start:start + 7].tolist()
        return (x, y, z), (qx, qy, qz, qw)

    def _holds(self, policy, num_steps):
        """
        Return until(step): the step up to which the torques of `step` stay the same.

        An open-loop torque policy's rows are known: the loop steps in C (mj_step's nstep)
        until they change or an event comes, bit for bit the steps one at a time. A PD
        policy's torques depend on the state: one step at a time.
        """
        if not isinstance(policy, TorquePolicy) or not self.chunked:
            return lambda step: step + 1
        rows = policy.schedule(num_steps)
        if self._hold_rows is not rows:
            until = [num_steps] * num_steps
            for step in range(num_steps - 2, -1, -1):
                until[step] = step + 1 if rows[step + 1] != rows[step] else until[step + 1]
            self._hold_rows, self._hold_until = rows, until
        return self._hold_until.__getitem__

    def _native(self, policy, num_steps):
        """Return the PD law of `policy` in C (NativePD), or None to step it in Python."""
        if (isinstance(policy, TorquePolicy) or not self.native
                or mujoco_native.library() is None):
            return None
        law = self._native_law
        if law is None or law[0] is not policy or law[1] != num_steps:
            law = self._native_law = (policy, num_steps,
                                      mujoco_native.NativePD(policy, num_steps))
        return law[2]

    def _run(self, policy, plan, trace, state, on_frame):
        m, d = self.mj_model, self.mj_data
        if self._scratch is None and not isinstance(policy, TorquePolicy):
            self._scratch = mujoco.MjData(m)
        native = self._native(policy, plan.num_steps)
        if native is not None:
            return play(plan, trace, state, native.advancer(m, d, self._scratch),
                        self.object_pose, self._stable, on_frame, self)
        torques = mujoco_torques(policy, m, d, plan.num_steps, self._scratch)
        until = self._holds(policy, plan.num_steps)
        joints = self._joints
        applied = d.qfrc_applied
        step_many = mujoco.mj_step

        def advance(done, stop):
            while done < stop:
                applied[:joints] = torques(done)
                held = min(until(done), stop)
                step_many(m, d, held - done)
                done = held

        return play(plan, trace, state, advance, self.object_pose, self._stable,
                    on_frame, self)

    def _stable(self, position, orientation, start, check_joints):
        """Return False for a diverged, non-finite or exploded object or (if asked) hand."""
        views = self._views
        counts = views.warnings
        if any(counts[kind] for kind in _DIVERGENCE_WARNINGS):
            return False
        if not object_intact(position, orientation, start):
            return False
        if check_joints:
            joints = self._joints
            return joints_intact(views.qpos[:joints].tolist(), views.qvel[:joints].tolist())
        return True

    def link_poses(self):
        """Return the world pose (position, quaternion x, y, z, w) of every link frame."""
        d, first = self.mj_data, self._palm_body + 1
        mujoco.mj_kinematics(self.mj_model, d)  # from qpos (the next step recomputes it anyway)
        poses = []
        for body in range(first, first + self._joints):
            w, x, y, z = d.xquat[body].tolist()
            poses.append((tuple(d.xpos[body].tolist()), (x, y, z, w)))
        return poses

    def joint_angles(self):
        """Return the hand's joint angles (rad), in joint order."""
        return self.mj_data.qpos[:self._joints].tolist()

    def touching_links(self, distance):
        """
        Return the indices of the links with a contact at most `distance` (m) from the object.

        Contacts up to TOUCH_MARGIN apart are detected (the object's gap) but inactive (its
        margin is 0), so reading them changes nothing in the physics.
        """
        m, d = self.mj_model, self.mj_data
        mujoco.mj_kinematics(m, d)
        mujoco.mj_collision(m, d)
        links = set()
        for contact in d.contact[:d.ncon]:
            one, two = contact.geom
            other = two if one == self._object_geom else one if two == self._object_geom else -1
            if other in self._hand_geoms and contact.dist <= distance:
                links.add(int(m.geom_bodyid[other]) - self._palm_body - 1)  # palm: -1
        return links

    def joint_states(self):
        """Return the hand's joint angles (rad) and speeds (rad/s) as lists."""
        d, joints = self.mj_data, self._joints
        return d.qpos[:joints].tolist(), d.qvel[:joints].tolist()


def mujoco_torques(policy, m, d, num_steps, scratch=None):
    """
    Return torques(step) -> joint torques of a core.policies policy on a MuJoCo scene.

    Torque policy: its rows (gravity compensation, if any, is the model's gravcomp). PD
    policy: eq. (1) in the stable form of core.policies, M a + C(theta, thetad) thetad_d by
    the same polarization of inverse dynamics (mj_rne on a scratch MjData); N(theta) is the
    model's gravcomp when the policy compensates gravity. `scratch`: an MjData of a model of
    the same sizes for the PD law's inverse dynamics (default: a new one).
    """
    if isinstance(policy, TorquePolicy):
        return policy.schedule(num_steps).__getitem__
    target_rows, velocity_rows = policy.track(num_steps)
    gains = policy.step_gains()
    joints = policy.num_joints
    scratch = mujoco.MjData(m) if scratch is None else scratch
    result = np.zeros(m.nv)

    def inverse_dynamics(velocities, accelerations):
        scratch.qvel[:joints] = velocities
        scratch.qacc[:joints] = accelerations
        mujoco.mj_comVel(m, scratch)
        mujoco.mj_rne(m, scratch, 1, result)
        return result[:joints].copy()

    def torques(step):
        angles, velocities = d.qpos[:joints].tolist(), d.qvel[:joints].tolist()
        targets, target_velocities = target_rows[step], velocity_rows[step]
        twice_a = [-(kd * edot + kp * (q - qd + h * edot)) * scale
                   for (kp, kd, h, scale), q, qd, edot
                   in zip(gains, angles, targets,
                          [v - vd for v, vd in zip(velocities, target_velocities)])]
        scratch.qpos[:] = d.qpos
        mujoco.mj_kinematics(m, scratch)
        mujoco.mj_comPos(m, scratch)
        plus = inverse_dynamics([v + vd for v, vd in zip(velocities, target_velocities)],
                                twice_a)
        minus = inverse_dynamics([v - vd for v, vd in zip(velocities, target_velocities)],
                                 [-a for a in twice_a])
        return ((plus - minus) * 0.25).tolist()
    return torques
