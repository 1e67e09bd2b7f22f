"""
A simulated test rig: the stand-in for a built hand, for tests and demos.

It simulates with the run's physics engine, or with the other one (`engine`): a rig on
MuJoCo measuring designs found on PyBullet shows a real gap between two physics in the
rig's prediction-against-measurement report.

It builds the requested hand with the core's own builder (`hand_model`, `Simulator.build`) from
a Candidate's physical values (`core.sim.physical.design_from_physical`), never from the genome,
and runs a trial (a `core.rig.trials.TrialSpec`) as the simulator runs a world: start collision
check of that world, then the rollout, reading the object's pose at the rig's sample times. The
scene of a trial is built afresh, as `core.evaluate` builds it for every candidate, so the
poses are those of the simulated evaluation bit for bit.

The rig knows nothing of the goals: its rollout is the task's without early termination or
horizon (the same physics up to any check; it runs to the task's last goal). Sample times:
every physics step (`rate` 0), or at `rate` Hz with a `phase` (a fraction of a sample period:
a motion capture clock is not synchronized with the trial), each sample taken at the physics
step nearest to it and stamped with that step's time, and at the trial's end. Optional
Gaussian noise (m, rad) from a seeded generator.
"""

from dataclasses import dataclass
import math

from hand_codesign.core.evaluate import new_simulator
from hand_codesign.core.rig.trials import TrialSpec
from hand_codesign.core.run.evaluation_jobs import candidate_task, CandidateRejected
from hand_codesign.core.sim.hand import hand_model
from hand_codesign.core.sim.objectives import goal_schedule, quaternion_multiply
from hand_codesign.core.sim.physical import design_from_physical
from hand_codesign.core.sim.policies import make_policy
from hand_codesign.core.sim.worlds import ObjectState
import numpy as np


@dataclass(frozen=True)
class SampleClock:
    """When a rig measures the object: every step (rate 0) or at rate Hz with a phase."""

    rate: float = 0.0
    phase: float = 0.0

    def steps(self, time_step, num_steps):
        """Return the set of physics steps, 0 to num_steps, at which a pose is published."""
        if self.rate <= 0:
            return set(range(num_steps + 1))
        period = 1.0 / self.rate
        count = int(math.floor(num_steps * time_step / period - self.phase + 1e-9))
        steps = {int(round((n + self.phase) * period / time_step)) for n in range(count + 1)}
        return steps | {num_steps}   # and the pose at the trial's end, as it ends


def rig_task(task):
    """Return the task a rig runs: the same physics, no early termination, no horizon."""
    return task.replace(early_termination=None, horizon=None)


class SimulatedRig:
    """Run trials of physical designs in PyBullet; see the module doc."""

    def __init__(self, clock=SampleClock(), noise=(0.0, 0.0), seed=0, engine=''):
        self.engine = engine  # 'pybullet' or 'mujoco'; '' the run's
        self.simulators = {}
        self.clock = clock
        self.noise = tuple(float(n) for n in noise)
        self.random = np.random.default_rng(seed)

    def close(self):
        """Close the simulators."""
        for simulator in self.simulators.values():
            simulator.close()

    def simulator(self, task):
        """Return the simulator of this rig's engine (default: the task's)."""
        engine = self.engine or task.physics.engine
        if engine not in self.simulators:
            self.simulators[engine] = new_simulator(engine)
        return self.simulators[engine]

    def run(self, task, design, spec, on_pose):
        """
        Run one trial; call on_pose(t, position, orientation) at each sample; return status.

        Status: 'collision' (the hand starts touching itself, the ground or the object;
        nothing runs), 'unstable' (the simulation blew up; the trace stops there) or 'ok'.
        """
        task = rig_task(task)
        schedule = goal_schedule(task)
        model = hand_model(design.hand, task.hand)
        policy = make_policy(task.policy, design.controller, model.initial_angles,
                             task.time_step)
        state = ObjectState(position=tuple(spec.position), orientation=tuple(spec.orientation),
                            scale=spec.scale, mass=spec.mass, friction=spec.friction,
                            size=tuple(spec.size))
        simulator = self.simulator(task)
        simulator.build(task, model)
        shape = simulator.object_shape(state, spec.shape)
        if simulator.start_collisions([(state, shape)]):
            return 'collision'
        samples = self.clock.steps(task.time_step, simulator.plan(schedule).num_steps)

        def on_frame(step, sim):
            if step in samples:
                position, orientation = sim.object_pose()
                on_pose(step * task.time_step, *self._noisy(position, orientation))

        result = simulator.rollout(state, shape, policy, schedule, on_frame, 1)
        return 'unstable' if result.unstable else 'ok'

    def _noisy(self, position, orientation):
        position_noise, angle_noise = self.noise
        if position_noise > 0:
            position = tuple(np.asarray(position) + self.random.normal(0, position_noise, 3))
        if angle_noise > 0:
            axis = self.random.normal(size=3)
            axis /= np.linalg.norm(axis)
            angle = self.random.normal(0, angle_noise)
            turn = (*(axis * math.sin(angle / 2)), math.cos(angle / 2))
            orientation = quaternion_multiply(turn, orientation)
        return tuple(position), tuple(orientation)


def requested_trial(run, candidate, request):
    """
    Return (task, Design, TrialSpec) of a TrialRequest for a Candidate of run (a RunInfo).

    The Design comes from the Candidate's physical fields; the task gives what the rig
    itself is (hand sizes, time step, policy timing). ValueError says why it cannot run.
    """
    if not candidate.design_names:
        raise ValueError(f'candidate {candidate.candidate_id} carries no physical design '
                         '(design_names is empty)')
    try:
        task, _ = candidate_task(run, candidate)
    except CandidateRejected as error:
        raise ValueError(str(error)) from None
    design = design_from_physical(candidate.structure, candidate.design_names,
                                  candidate.design_values, candidate.controller_kind,
                                  candidate.controller_values, candidate.controller_kp,
                                  candidate.controller_kd)
    spec = TrialSpec(world=request.world, worlds=request.worlds, shape=request.object_shape,
                     size=tuple(request.object_size), scale=request.object_scale,
                     position=tuple(request.object_position),
                     orientation=tuple(request.object_orientation), mass=request.object_mass,
                     friction=request.object_friction, duration=request.duration)
    return task, design, spec
