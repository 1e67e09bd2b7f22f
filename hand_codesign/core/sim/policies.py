"""
Control policies of section III.B: joint torques over time and the feed-forward PD law.

A policy turns a ControllerDesign into joint torques, one row per physics step. The simulator
calls `policy.start(client, body, num_steps)` once per rollout and gets back a function
`torques(step) -> list` that it calls every step; everything that does not depend on the
hand's state is computed there once, so an open-loop policy costs one list lookup per step.

TorquePolicy: K torques per joint. Mode 'constant' holds torque k over [k D / K, (k+1) D / K);
mode 'interpolated' places torque k at k D / (K - 1) and interpolates linearly (D the policy
duration). After D the policy torque is zero. With gravity compensation the torques that
hold the hand still against gravity, N(theta) = ID(theta, 0, 0) from PyBullet's inverse
dynamics, are added every step. Its peak |tau| is the tau* of the torque penalty, eq. (2).

Gravity in inverse dynamics: PyBullet's calculateInverseDynamics ignores the pose of a fixed
base (it puts the base at the world origin, unrotated), so with the world's gravity it
compensates gravity as if the palm were not turned: every preset turns it (palm up or palm
down), and a hand of Task 1 then fell over under "compensation". N is therefore computed with
gravity turned into the base frame, set for that one call and set back before the step
(`GravityCompensation`); M and C do not depend on the base's orientation.

PDPolicy, equation (1) with the gains multiplied by M(theta) as the paper does:
    tau = M(theta) (thetadd_d - Kv edot - Kp e) + C(theta, thetad) thetad_d + N(theta),
    e = theta - theta_d,  edot = thetad - thetad_d.
The targets theta_d run linearly from the initial joint angles at t = 0 through keyframe k at
keyframe time k, then hold the last keyframe: thetad_d is the slope of the current piece and
thetadd_d is zero. M, C and N come from PyBullet's inverse dynamics ID(q, v, a) =
M(q) a + C(q, v) v + N(q) alone. The Coriolis term C(q, v) v is a symmetric bilinear form
B(v, v) (Christoffel symbols are symmetric in their last two indices), so polarization gives
    M a + C(theta, thetad) thetad_d = [ID(theta, thetad + thetad_d, 2a)
                                       - ID(theta, thetad - thetad_d, -2a)] / 4
exactly, and N(theta) (above) is added when gravity compensation is on (the default for
PD). Three inverse-dynamics calls per step, no mass matrix inversion.

Stability: the PD is integrated stably, after Tan, Liu and Turk 2011, "Stable
Proportional-Derivative Controllers". Because the gains are multiplied by M(theta), eq. (1)
makes every joint, apart from contacts, the unit-mass system edd = -Kv edot - Kp e. Bullet
integrates it semi-implicitly (v += a dt, then theta += v dt); per joint that step has the
determinant 1 - Kv dt and the trace 2 - Kv dt - Kp dt^2, so it diverges once
Kv dt + Kp dt^2 / 2 > 2, for Kv above about 390 to 400 at dt = 0.005 s, while Table I's D gains
reach 625. Measured (bench/bench_pd.py, seed hands of Tasks 1 and 2, Kp = 1000): at Kv = 400
the Task 1 joints oscillate (0.18 rad RMS off their targets); from Kv = 420 they sit at
Bullet's cap of 100 rad/s, reversing every step, for 89 % (Task 1) and 14 % (Task 2) of the
steps, 98 % and 94 % at Kv = 625; the cap keeps the state finite, so the instability check
(1e5 rad/s) never fires. The stable form evaluates the error at the end of the step:
    edd = -Kv (edot + dt edd) - Kp (e + dt edot)
    =>  a = -(Kv edot + Kp (e + dt edot)) / (1 + Kv dt),
a division per joint (M(theta) has already decoupled the joints, so no matrix is solved),
stable for every Kv >= 0 and Kp dt^2 < 4/3 (Kp < 53,000 at dt = 0.005 s). Measured: no joint
ever at the cap over Table I's gains; the hand alone follows the joint angles of eq. (1)
integrated explicitly at dt / 10 (the reference) to 0.004 rad RMS; holding the Task 2 sphere
it is the closest to that reference, or tied, at every gain tried (0.014 to 0.064 rad RMS;
the explicit law 0.024 to 0.072 where it is stable, a law with only the damping implicit
0.014 to 0.077); with Task 1's capsule, contact makes every form, the explicit law at low
gains too, differ from the reference by 0.09 to 0.14 rad, which does not tell them apart.
torques() costs the same as the explicit law's (ratio 1.00). Its price: a force the law does
not model (contact) meets the stiffness Kp / (1 + Kv dt) in steady state (Task 5's
Kv dt <= 0.05 keeps it within 5 % of Kp). Not chosen: charging saturated rollouts as unstable
(over a third of Table I's D range, where eq. (1) tracks in continuous time, would be
forbidden); clamping torques (by the analysis above the clamped loop still overshoots every
step, now by the clamp; not measured); Bullet's implicit motor (POSITION_CONTROL with gains is
not eq. (1)'s torque and leaves no torque to read). The torques stay explicit values sent
with TORQUE_CONTROL and depend only on the current state, so evaluations stay pure and
bit-identical. `stable=False` gives eq. (1) explicitly, the reference of those measurements.
"""

import numpy as np


def torque_knot_times(mode, knots, duration):
    """Return the times of the K torque knots: interval starts or interpolation points."""
    if mode == 'constant':
        return np.arange(knots) * (duration / knots)
    if mode == 'interpolated':
        if knots < 2:
            raise ValueError(f'interpolated torques need at least 2 knots, got {knots}')
        return np.linspace(0.0, duration, knots)
    raise ValueError(f'torque mode {mode!r}: expected constant or interpolated')


def _joint_angles(client, body, joint_indices):
    return [state[0] for state in client.getJointStates(body, joint_indices)]


class GravityCompensation:
    """N(theta): the joint torques that hold a fixed-base body still against gravity."""

    def __init__(self, client, body, num_joints):
        parameters = client.getPhysicsEngineParameters()
        self.world_gravity = [parameters[f'gravityAcceleration{axis}'] for axis in 'XYZ']
        _, orientation = client.getBasePositionAndOrientation(body)
        rotation = np.array(client.getMatrixFromQuaternion(orientation)).reshape(3, 3)
        self.base_gravity = (rotation.T @ np.array(self.world_gravity)).tolist()
        self.client, self.body = client, body
        self.zeros = [0.0] * num_joints

    def __call__(self, angles):
        """Return N(angles) (see the module doc: gravity in the base frame for the call)."""
        client = self.client
        client.setGravity(*self.base_gravity)
        try:
            return client.calculateInverseDynamics(self.body, angles, self.zeros, self.zeros)
        finally:
            client.setGravity(*self.world_gravity)


def _joint_states(client, body, joint_indices):
    states = client.getJointStates(body, joint_indices)
    return [state[0] for state in states], [state[1] for state in states]


class TorquePolicy:
    """Piecewise-constant or interpolated joint torques, optionally gravity compensated."""

    def __init__(self, values, duration, mode='constant', gravity_compensation=False,
                 time_step=0.005):
        self.values = np.atleast_2d(np.asarray(values, dtype=float))
        self.duration = float(duration)
        self.mode = mode
        self.gravity_compensation = bool(gravity_compensation)
        self.time_step = float(time_step)
        self.knot_times = torque_knot_times(mode, len(self.values), self.duration)
        self._schedules = {}

    @property
    def num_joints(self):
        return self.values.shape[1]

    @property
    def peak_torque(self):
        """Return tau* = max |tau_i| over the policy's torque values (eq. 2)."""
        return float(np.max(np.abs(self.values))) if self.values.size else 0.0

    def torque_at(self, times):
        """Return the policy torques (len(times) x joints) at the given times, in seconds."""
        times = np.atleast_1d(np.asarray(times, dtype=float))
        if self.mode == 'constant':
            knot = np.searchsorted(self.knot_times, times, side='right') - 1
            torques = self.values[np.clip(knot, 0, len(self.values) - 1)]
        else:
            torques = np.stack([np.interp(times, self.knot_times, column)
                                for column in self.values.T], axis=1)
        # A tolerance of a millionth of a step keeps t = D itself out of the policy.
        after = times >= self.duration - 1e-6 * self.time_step
        return np.where(after[:, None], 0.0, torques)

    def schedule(self, num_steps):
        """Return the torques of steps 0..num_steps-1 as a list of rows (step k at k dt)."""
        if num_steps not in self._schedules:
            times = np.arange(num_steps) * self.time_step
            self._schedules[num_steps] = self.torque_at(times).tolist()
        return self._schedules[num_steps]

    def start(self, client, body, num_steps):
        """Return torques(step) -> list of joint torques for one rollout of `body`."""
        rows = self.schedule(num_steps)
        if not self.gravity_compensation:
            return rows.__getitem__
        joints = list(range(self.num_joints))
        angles, gravity = _joint_angles, GravityCompensation(client, body, self.num_joints)

        def torques(step):
            hold = gravity(angles(client, body, joints))
            return [tau + n for tau, n in zip(rows[step], hold)]
        return torques


class PDPolicy:
    """
    The feed-forward PD controller of equation (1) tracking keyframed joint targets.

    stable=True (the default) integrates it in the stable form of the module doc;
    stable=False applies eq. (1) explicitly (unstable for Kv dt + Kp dt^2 / 2 > 2).
    """

    def __init__(self, targets, keyframe_times, kp, kd, initial_angles,
                 gravity_compensation=True, time_step=0.005, stable=True):
        self.targets = np.atleast_2d(np.asarray(targets, dtype=float))
        self.keyframe_times = np.asarray(keyframe_times, dtype=float)
        self.kp = np.asarray(kp, dtype=float)
        self.kd = np.asarray(kd, dtype=float)
        self.initial_angles = np.asarray(initial_angles, dtype=float)
        self.gravity_compensation = bool(gravity_compensation)
        self.time_step = float(time_step)
        self.stable = bool(stable)
        if len(self.keyframe_times) != len(self.targets):
            raise ValueError(f'{len(self.targets)} keyframes for {len(self.keyframe_times)} '
                             'keyframe times; expected one time per keyframe')
        if np.any(np.diff(np.concatenate([[0.0], self.keyframe_times])) <= 0):
            raise ValueError(f'keyframe times {self.keyframe_times.tolist()}: expected '
                             'strictly increasing times after 0')
        self._tracks = {}

    @property
    def num_joints(self):
        return self.targets.shape[1]

    @property
    def peak_torque(self):
        """Return 0: a PD policy has no torque parameters to penalize (eq. 2)."""
        return 0.0

    def target_at(self, times):
        """Return (theta_d, thetad_d) at the given times, each len(times) x joints."""
        times = np.atleast_1d(np.asarray(times, dtype=float))
        knot_times = np.concatenate([[0.0], self.keyframe_times])
        knots = np.vstack([self.initial_angles, self.targets])
        piece = np.clip(np.searchsorted(knot_times, times, side='right') - 1,
                        0, len(knot_times) - 2)
        span = knot_times[piece + 1] - knot_times[piece]
        slope = (knots[piece + 1] - knots[piece]) / span[:, None]
        inside = (times < knot_times[-1])[:, None]
        position = np.where(inside, knots[piece] + slope * (times - knot_times[piece])[:, None],
                            knots[-1])
        velocity = np.where(inside, slope, 0.0)
        return position, velocity

    def track(self, num_steps):
        """Return (theta_d rows, thetad_d rows) of steps 0..num_steps-1 as lists."""
        if num_steps not in self._tracks:
            position, velocity = self.target_at(np.arange(num_steps) * self.time_step)
            self._tracks[num_steps] = (position.tolist(), velocity.tolist())
        return self._tracks[num_steps]

    def step_gains(self):
        """
        Return (kp, kd, h, 2 / (1 + h kd)) per joint, the constants of one step's law.

        a = -(kd edot + kp (e + h edot)) / (1 + h kd) with h the time step (stable form), or
        with h = 0 (explicit form); the factor 2 is that of the polarization identity.
        """
        h = self.time_step if self.stable else 0.0
        return [(kp, kd, h, 2.0 / (1.0 + h * kd))
                for kp, kd in zip(self.kp.tolist(), self.kd.tolist())]

    def start(self, client, body, num_steps):
        """Return torques(step) -> list of joint torques for one rollout of `body`."""
        target_rows, velocity_rows = self.track(num_steps)
        joints = list(range(self.num_joints))
        gains = self.step_gains()
        states, inverse_dynamics = _joint_states, client.calculateInverseDynamics
        gravity = (GravityCompensation(client, body, self.num_joints)
                   if self.gravity_compensation else None)

        def torques(step):
            angles, velocities = states(client, body, joints)
            targets, target_velocities = target_rows[step], velocity_rows[step]
            # thetadd_d is zero on linear pieces: a = -(Kv edot + Kp (e + h edot)) / (1 + h Kv)
            # in the stable form, -Kv edot - Kp e in the explicit one (see step_gains).
            twice_a = [-(kd * edot + kp * (q - qd + h * edot)) * scale
                       for (kp, kd, h, scale), q, qd, edot
                       in zip(gains, angles, targets,
                              [v - vd for v, vd in zip(velocities, target_velocities)])]
            plus = inverse_dynamics(body, angles,
                                    [v + vd for v, vd in zip(velocities, target_velocities)],
                                    twice_a)
            minus = inverse_dynamics(body, angles,
                                     [v - vd for v, vd in zip(velocities, target_velocities)],
                                     [-a for a in twice_a])
            tau = [(p - m) * 0.25 for p, m in zip(plus, minus)]
            if gravity is not None:
                tau = [t + n for t, n in zip(tau, gravity(angles))]
            return tau
        return torques


def make_policy(policy_spec, controller, initial_angles, time_step):
    """Return the policy of a task's PolicySpec with a candidate's ControllerDesign."""
    if controller.kind != policy_spec.kind:
        raise ValueError(f'controller kind {controller.kind!r} for a {policy_spec.kind!r} '
                         'policy; expected the same kind')
    if policy_spec.kind == 'torque':
        return TorquePolicy(controller.values, policy_spec.duration, policy_spec.mode,
                            policy_spec.gravity_compensation, time_step)
    return PDPolicy(controller.values, policy_spec.keyframe_times, controller.kp,
                    controller.kd, initial_angles, policy_spec.gravity_compensation,
                    time_step)
