"""
The PyBullet world of a candidate and the one rollout loop.

A Simulator owns one physics client (DIRECT, never the global client). Per candidate,
`build(task, hand_model)` resets the simulation and builds the ground and the hand; per
world, `rollout` puts the hand's joints back to their initial angles at rest, creates the
world's object (its own collision shape: worlds differ in scale, mass, friction and pose),
runs the loop and removes the object again, so every world starts from exactly the state of
a freshly built scene. That is all that saveState/restoreState would restore here (Bullet
restores the multibodies' base poses, velocities and joint states), without saveState's
0.8 ms of serialization per candidate; test_sim.py checks that every world's rollout is
bit-identical to one in a fresh world, in any order, also after rollouts that ended with the
hand pressing the ground (deterministicOverlappingPairs keeps the pair order independent of
history). Measured on this platform: rebuilding per rollout costs 15-40 %; resetSimulation
per candidate keeps memory flat (create + remove without a reset leaks about 13 KB per body).
Unloading the TinyRenderer plugin (which converts every collision shape into a visual shape)
makes building a 2x3 hand about 5 times faster; pass rendering=True to keep it for
getCameraImage.

Physics settings: the task's time step, its `physics` section (50 solver iterations and a
contact breaking threshold of 2 cm unless it says otherwise), deterministic overlapping
pairs, and no split impulse (with split impulse, Bullet's multibody joint limits never push a
joint back and a fast finger overshoots its limit). Bullet multiplies the friction
coefficients of two touching bodies; the ground's is 1, so the object slides on the ground
with its own coefficient and touches the hand with the product of both.

Where a step's time goes (callgrind, Task 5 with Table I's physics): about 70 % in Bullet's
multibody constraint solver (its 50 iterations over the contact, friction and joint-limit rows
and their setup), 14 % in collision detection, 10 % in the hand's forward dynamics; the Python
calls per step (torques, step) cost about 2 us of 15 to 20. Stepping several worlds' scenes in
one client would save only those calls, so a faster step needs fewer solver iterations or
contact rows: the task's `physics` section (bench/bench_physics.py).

The rollout loop (core.sim.events.play, shared with MuJoCo) looks at the world at its
events only; between them this engine applies the policy's torques to every joint in one
TORQUE_CONTROL call each step (the default velocity motors are off) and steps.

Unstable simulation: a non-finite or exploding state (object farther than EXPLOSION_DISTANCE
from its start, a non-finite joint or one faster than EXPLOSION_JOINT_SPEED, both in
core.sim.scene; core.sim.events' object_intact and joints_intact check them, for both engines)
ends the rollout with `Rollout.unstable` set; evaluate() charges every objective of that world
UNSTABLE_PENALTY.
(Bullet itself caps joint speeds at 100 rad/s, btMultiBody's maximum coordinate velocity, so
huge torques fling a finger but do not blow the joints up.)

Start collisions: `start_collisions(objects)` reports whether the hand touches itself
(non-adjacent links, after performCollisionDetection), the ground or the object of any world
at the start, penetrating deeper than COLLISION_TOLERANCE.
"""

from functools import partial
from typing import Callable, Optional

from hand_codesign.core.sim.events import EventPlans, joints_intact, object_intact, play
from hand_codesign.core.sim.hand import build_hand, HandModel
from hand_codesign.core.sim.quiet_pybullet import BulletClient, c_output_silenced, pybullet
from hand_codesign.core.sim.scene import COLLISION_TOLERANCE, GRAVITY, GROUND_FRICTION

# The ground is a box with its top face at z = 0: faster to build than a GEOM_PLANE.
GROUND_HALF_EXTENTS = (50.0, 50.0, 0.5)


def object_shape(client, state, shape):
    """Create the collision shape of an ObjectState of a `shape` object; return its id."""
    if shape == 'box':
        return client.createCollisionShape(client.GEOM_BOX,
                                           halfExtents=[s / 2 for s in state.size])
    if shape == 'sphere':
        return client.createCollisionShape(client.GEOM_SPHERE, radius=state.size[0])
    if shape == 'capsule':
        return client.createCollisionShape(client.GEOM_CAPSULE, radius=state.size[0],
                                           height=state.size[1])
    raise ValueError(f'object shape {shape!r}: expected box, sphere or capsule')


class Client(BulletClient):
    """
    A BulletClient that looks each PyBullet function up once.

    BulletClient builds a new partial function (and inspects it) at every attribute access,
    about 3 us; a candidate's build and worlds make over a hundred of them.
    """

    def __getattr__(self, name):
        attribute = super().__getattr__(name)
        self.__dict__[name] = attribute  # found directly from now on
        return attribute


class Simulator(EventPlans):
    """A PyBullet client with the scene of one candidate and the rollout loop."""

    engine = 'pybullet'

    def __init__(self, rendering=False):
        with c_output_silenced():
            self.client = Client(connection_mode=pybullet.DIRECT)
        if not rendering:
            self.client.unloadPlugin(self.client.loadPlugin('tinyRendererPlugin'))
        self.rendering = rendering
        self.task = None
        self.model = None
        self.hand = self.ground = None
        self.object_body = None
        self._joints = []
        self._initial_angles = []
        EventPlans.__init__(self)

    def close(self):
        """Disconnect the physics client."""
        if self.client is not None:
            self.client.disconnect()
            self.client = None

    def __enter__(self):
        return self

    def __exit__(self, *exc_info):
        self.close()

    # ---------------------------------------------------------------- scene

    def build(self, task, model: HandModel):
        """Reset the simulation and build ground and hand of one candidate on `task`."""
        client = self.client
        client.resetSimulation()
        physics = task.physics
        # contactBreakingThreshold is a process-wide Bullet setting: set it for every build.
        client.setPhysicsEngineParameter(
            fixedTimeStep=task.time_step, numSolverIterations=physics.solver_iterations,
            contactBreakingThreshold=physics.contact_breaking_threshold,
            deterministicOverlappingPairs=1, useSplitImpulse=0)
        client.setGravity(0.0, 0.0, GRAVITY)
        ground_shape = client.createCollisionShape(client.GEOM_BOX,
                                                   halfExtents=GROUND_HALF_EXTENTS)
        self.ground = client.createMultiBody(
            0.0, ground_shape, basePosition=(0.0, 0.0, -GROUND_HALF_EXTENTS[2]))
        client.changeDynamics(self.ground, -1, lateralFriction=GROUND_FRICTION)
        contact = physics.contact
        if contact is not None and contact.restitution is not None:
            # Bullet multiplies the two bodies' restitutions: a ground of 1 leaves the object's
            # own coefficient to its bounce, while the hand's (0) keeps fingers from bouncing
            client.changeDynamics(self.ground, -1, restitution=1.0)
        self.hand = build_hand(client, model, model.base_position, model.base_orientation)
        self.task, self.model = task, model
        self._joints = list(range(model.num_joints))
        self._initial_angles = list(model.initial_angles)
        self.object_body = None

    def reset_hand(self):
        """Put the hand's joints back to their initial angles, at rest."""
        reset = self.client.resetJointState
        for joint, angle in zip(self._joints, self._initial_angles):
            reset(self.hand, joint, angle, 0.0)

    def start_collisions(self, objects):
        """
        Return True if the hand starts in contact with itself, the ground or any object.

        `objects` is a list of (ObjectState, collision shape id) of the worlds.
        """
        client = self.client
        client.performCollisionDetection()
        depth = -COLLISION_TOLERANCE
        if any(point[8] < depth for point in client.getContactPoints(self.hand, self.hand)):
            return True
        ground_points = client.getClosestPoints(self.hand, self.ground, 0.0)
        if any(point[8] < depth for point in ground_points):
            return True
        for state, shape in objects:
            points = client.getClosestPoints(self.hand, -1, 0.0, collisionShapeB=shape,
                                             collisionShapePositionB=state.position,
                                             collisionShapeOrientationB=state.orientation)
            if any(point[8] < depth for point in points):
                return True
        return False

    def object_shape(self, state, shape):
        """Return the collision shape id of a world's object (ObjectState, task shape name)."""
        return object_shape(self.client, state, shape)

    def create_object(self, state, shape):
        """
        Create the object of one world (an ObjectState) from its collision shape.

        The object is a rigid body (maximal coordinates), not a one-link multibody: on the
        Task 5 scene that makes whole evaluations about 9 % faster.
        """
        body = self.client.createMultiBody(state.mass, shape, basePosition=state.position,
                                           baseOrientation=state.orientation,
                                           useMaximalCoordinates=True)
        self.client.changeDynamics(body, -1, lateralFriction=state.friction)
        if state.contact is not None:
            self._set_contact(body, state.contact)
        self.object_body = body
        return body

    def _set_contact(self, body, contact):
        """
        Give the object a world's contact parameters (core.sim.worlds.ContactState).

        Why on the object alone: every contact it makes (ground, hand) takes them, as in
        MuJoCo's object geom and its ground pair, while the hand's own contacts stay Bullet's.
        Bullet combines two bodies' stiffnesses in series and adds their dampings: the
        ground's and the hand's defaults (about 1e18 N/m, 0.1 N s/m) leave the object's
        stiffness and add 0.1 N s/m to its damping. Bullet solves the spring-damper
        implicitly (an ERP and CFM per contact point), so any stiffness is stable, and each
        contact point is one such spring: a box resting on four corners is four times as
        stiff as a sphere on one. Restitution acts above Bullet's restitution velocity
        threshold (0.2 m/s), on top of the damping.
        """
        if contact.stiffness is not None:
            self.client.changeDynamics(body, -1, contactStiffness=contact.stiffness,
                                       contactDamping=contact.damping)
        if contact.restitution is not None:
            self.client.changeDynamics(body, -1, restitution=contact.restitution)

    def object_pose(self):
        """Return the current object's (position, orientation x, y, z, w)."""
        return self.client.getBasePositionAndOrientation(self.object_body)

    def link_poses(self):
        """Return the world pose (position, quaternion x, y, z, w) of every link frame."""
        links = self.client.getLinkStates(self.hand, self._joints,
                                          computeForwardKinematics=True)
        return [(tuple(link[4]), tuple(link[5])) for link in links]

    def touching_links(self, distance):
        """Return the set of the hand's links with a contact point at most `distance` (m)."""
        return {point[3] for point in self.client.getContactPoints(self.hand, self.object_body)
                if point[8] <= distance}

    def joint_angles(self):
        """Return the hand's joint angles (rad), in joint order."""
        return [state[0] for state in self.client.getJointStates(self.hand, self._joints)]

    def remove_object(self):
        """Remove the current world's object (the scene is back to ground and hand)."""
        if self.object_body is not None:
            self.client.removeBody(self.object_body)
            self.object_body = None

    # ---------------------------------------------------------------- rollout

    def rollout(self, state, shape, policy, schedule,
                on_frame: Optional[Callable] = None, frame_every=1,
                on_end: Optional[Callable] = None):
        """
        Run one world from the start of the scene: return a Rollout.

        `state`/`shape`: the world's ObjectState and its collision shape; `policy`: a policy
        of hand_codesign.core.sim.policies; `schedule`: the task's objectives.GoalSchedule.
        `on_frame(step, simulator)` is called at step 0 and every `frame_every` steps (the
        loop pays nothing for it when it is None). `on_end(simulator, rollout)` is called once
        after the loop, with the object still in the scene (core.outcomes reads it there).
        """
        self.reset_hand()
        body = self.create_object(state, shape)
        plan = self.plan(schedule, frame_every if on_frame is not None else 0)
        trace = schedule.new_trace(state)
        try:
            result = self._run(body, policy, plan, trace, state, on_frame)
            if on_end is not None:
                on_end(self, result)
            return result
        finally:
            self.remove_object()

    def _run(self, body, policy, plan, trace, state, on_frame):
        client, hand, joints = self.client, self.hand, self._joints
        torques = policy.start(client, hand, plan.num_steps)
        set_torques = client.setJointMotorControlArray
        step_simulation = client.stepSimulation
        torque_control = pybullet.TORQUE_CONTROL

        def advance(done, stop):
            for step in range(done, stop):
                set_torques(hand, joints, torque_control, forces=torques(step))
                step_simulation()

        return play(plan, trace, state, advance,
                    partial(client.getBasePositionAndOrientation, body), self._stable,
                    on_frame, self)

    def _stable(self, position, orientation, start, check_joints):
        """Return False for a non-finite or exploded object or (if asked) hand."""
        if not object_intact(position, orientation, start):
            return False
        if check_joints:
            states = self.client.getJointStates(self.hand, self._joints)
            return joints_intact([state[0] for state in states], [state[1] for state in states])
        return True
