"""
Benchmark of the PD controller's stability at Table I's gains (Tasks 1 and 2, dt = 0.005 s).

Runs the seed designs of config/tasks/task1.yaml and task2.yaml (hands with segments of about
0.5 kg) with their keyframes and the gains set to points of Table I's ranges, in three forms
of eq. (1) at the task's step:
  explicit   eq. (1) applied as it stands (PDPolicy(stable=False))
  stable     the stable form of hand_codesign/core/sim/policies.py (the default)
  damping    only the damping taken implicitly: Kv replaced by Kv / (1 + Kv dt) (an
             alternative, defined here)
and as the reference eq. (1) explicit at a ten times finer step (dt / 10 is explicitly
stable up to Kv = 4000). Prints per form:
  at cap     share of steps at which some joint moves at 99 rad/s or faster (Bullet caps
             joint speeds at 100 rad/s)
  flips      share of steps at which some joint at the cap reverses direction
  track      RMS of theta - theta_d (rad) over joints and steps, the hand alone (the world's
             object moved 20 m away)
  dev free   RMS difference of the joint angles from the reference's, the hand alone
  dev obj    the same in the task's worlds (with the object: contact)
  unstable   worlds the rollout's instability check caught (with the object)
  fitness    weighted objectives (eq. 5 and 6) averaged over the worlds (with the object)
Then the cost of the controller alone: the CPU time of the stable form's torques(step) as a
ratio of the explicit form's, both called in turn for every step of a Task 1 rollout at the
seed's start state (no stepping, so the same work each time).

Usage: python bench/bench_pd.py [--worlds N]    (default 2 worlds per task; about 2 minutes)
"""

import argparse
import dataclasses
import os
import time

from hand_codesign.core.sim.hand import hand_model
from hand_codesign.core.sim.objectives import goal_schedule, weighted_fitness
from hand_codesign.core.sim.policies import PDPolicy
from hand_codesign.core.sim.pybullet_sim import object_shape, Simulator
from hand_codesign.core.sim.worlds import object_state, world_states
from hand_codesign.core.task import load_task
import numpy as np

TASKS = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'config', 'tasks')
CAP = 99.0  # rad / s: at Bullet's cap of 100 rad/s
GAINS = [(1000.0, 100.0), (1000.0, 300.0), (1000.0, 400.0), (1000.0, 420.0),
         (1000.0, 450.0), (1000.0, 625.0), (100.0, 625.0), (5000.0, 625.0), (5000.0, 12.5)]
AWAY = 20.0  # m along x: where the runs of the hand alone put the object
FINE = 10  # the reference's step is the task's divided by FINE


class DampingOnlyPolicy(PDPolicy):
    """Eq. (1) with only its damping implicit: a = -Kp e - Kv edot / (1 + Kv dt)."""

    def step_gains(self):
        """Return the explicit law's constants with Kv / (1 + Kv dt) for Kv."""
        h = self.time_step
        return [(kp, kd / (1.0 + h * kd), 0.0, 2.0)
                for kp, kd in zip(self.kp.tolist(), self.kd.tolist())]


FORMS = {'explicit': (PDPolicy, {'stable': False}), 'stable': (PDPolicy, {'stable': True}),
         'damping': (DampingOnlyPolicy, {})}


class Recorder:
    """Collects joint angles and speeds at the frames of one rollout."""

    def __init__(self, joints):
        self.joints = joints
        self.angles, self.speeds = [], []

    def __call__(self, step, simulator):
        states = simulator.client.getJointStates(simulator.hand, self.joints)
        self.angles.append([state[0] for state in states])
        self.speeds.append([state[1] for state in states])


def rollouts(task, simulator, objects, form, kp, kd, fine=1):
    """Return ([(angles, speeds, Rollout)] of the seed design over `objects`, policy)."""
    if fine > 1:
        task = task.replace(time_step=task.time_step / fine)
    design = task.seed_design
    model = hand_model(design.hand, task.hand)
    joints = model.num_joints
    policy_class, options = FORMS[form]
    policy = policy_class(design.controller.values, task.policy.keyframe_times, [kp] * joints,
                          [kd] * joints, model.initial_angles,
                          task.policy.gravity_compensation, task.time_step, **options)
    schedule = goal_schedule(task)
    simulator.build(task, model)
    shapes = [(state, object_shape(simulator.client, state, task.object_spec.shape))
              for state in objects]
    if simulator.start_collisions(shapes):
        raise SystemExit(f'{task.source}: the seed design starts in collision')
    results = []
    for state, shape in shapes:
        recorder = Recorder(list(range(joints)))
        result = simulator.rollout(state, shape, policy, schedule, recorder, fine)
        results.append((np.array(recorder.angles), np.array(recorder.speeds), result))
    return results, policy


def deviation(runs, references):
    """Return the RMS difference of joint angles over the steps both rollouts reached."""
    squares = []
    for (angles, *_), (reference, *_) in zip(runs, references):
        steps = min(len(angles), len(reference))
        squares.append(np.mean((angles[:steps] - reference[:steps]) ** 2))
    return float(np.sqrt(np.mean(squares)))


def row(task, runs, free_runs, policy, references, free_references):
    """Return the printed figures of one form (see the module doc)."""
    at_cap, flips = [], []
    for _, speeds, _ in runs:
        capped = np.abs(speeds) >= CAP
        at_cap.append(np.mean(np.any(capped, axis=1)))
        flipped = capped[1:] & capped[:-1] & (np.sign(speeds[1:]) != np.sign(speeds[:-1]))
        flips.append(np.mean(np.any(flipped, axis=1)))
    track = []
    for angles, *_ in free_runs:
        targets, _ = policy.target_at(np.arange(len(angles)) * task.time_step)
        track.append(np.mean((angles - targets) ** 2))
    unstable = sum(result.unstable for _, _, result in runs)
    fitness = [weighted_fitness(result.trace.objective_values(), task.objective_weights)
               for _, _, result in runs if not result.unstable]
    return (f'{np.mean(at_cap):7.3f} {np.mean(flips):6.3f} {np.sqrt(np.mean(track)):6.3f} '
            f'{deviation(free_runs, free_references):8.3f} '
            f'{deviation(runs, references):7.3f} {unstable:8d} '
            f'{np.mean(fitness) if fitness else float("nan"):8.3f}')


def bench_task(name, worlds):
    """Print the table of one task."""
    task = load_task(os.path.join(TASKS, name))
    objects = [object_state(task, world) for world in world_states(task, worlds)]
    away = [dataclasses.replace(state, position=(state.position[0] + AWAY,) + tuple(
        state.position[1:])) for state in objects]
    print(f'{name}: seed design, {len(objects)} worlds, {task.duration:g} s, '
          f'dt {task.time_step:g} s; reference: explicit at dt / {FINE}')
    print(f'  {"kp":>5} {"kd":>5}  {"form":9} {"at cap":>7} {"flips":>6} {"track":>6} '
          f'{"dev free":>8} {"dev obj":>7} {"unstable":>8} {"fitness":>8}')
    with Simulator() as simulator:
        for kp, kd in GAINS:
            references, _ = rollouts(task, simulator, objects, 'explicit', kp, kd, FINE)
            free_references, _ = rollouts(task, simulator, away, 'explicit', kp, kd, FINE)
            fitness = np.mean([weighted_fitness(r.trace.objective_values(),
                                                task.objective_weights)
                               for _, _, r in references if not r.unstable])
            print(f'  {kp:5g} {kd:5g}  {"dt / 10":9} {"":40} {fitness:8.3f}')
            for form in FORMS:
                runs, policy = rollouts(task, simulator, objects, form, kp, kd)
                free_runs, _ = rollouts(task, simulator, away, form, kp, kd)
                print(f'  {"":5} {"":5}  {form:9} '
                      + row(task, runs, free_runs, policy, references, free_references))


def bench_cost(rounds=20):
    """Print the CPU time of the stable form's torques() as a ratio of the explicit form's."""
    task = load_task(os.path.join(TASKS, 'task1.yaml'))
    design = task.seed_design
    model = hand_model(design.hand, task.hand)
    steps = int(round(task.duration / task.time_step))
    best = {}
    with Simulator() as simulator:
        simulator.build(task, model)
        simulator.reset_hand()
        for _ in range(rounds):
            for stable in (False, True):
                policy = PDPolicy(design.controller.values, task.policy.keyframe_times,
                                  design.controller.kp, design.controller.kd,
                                  model.initial_angles, True, task.time_step, stable=stable)
                torques = policy.start(simulator.client, simulator.hand, steps)
                start = time.process_time()
                for step in range(steps):
                    torques(step)
                elapsed = time.process_time() - start
                best[stable] = min(best.get(stable, elapsed), elapsed)
    print(f'torques() per step, best of {rounds} rounds of {steps} calls: stable '
          f'{best[True] / steps * 1e6:.1f} us, explicit {best[False] / steps * 1e6:.1f} us, '
          f'ratio {best[True] / best[False]:.3f}')


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--worlds', type=int, default=2, help='worlds per task')
    args = parser.parse_args()
    for name in ('task1.yaml', 'task2.yaml'):
        bench_task(name, args.worlds)
    bench_cost()


if __name__ == '__main__':
    main()
