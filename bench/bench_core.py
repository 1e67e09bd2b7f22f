"""
Benchmark of the simulation core on the Task 5 scene (config/tasks/task5.yaml).

Prints, each against a reference measured in the same run (times are this process's CPU
time, so that other processes on the machine disturb the ratios less):
(a) the evaluation rate (physics steps per second of evaluate(), everything included: world
    build, collision check, objects, rollouts, objectives) as a ratio of a bare loop that
    only steps the same built worlds the same number of steps (target >= 0.90). Two bare
    loops: 'stepping only' calls stepSimulation alone (the hand hangs limp: different
    contacts, so a different load); 'same torques' also sends the candidate's torques each
    step, so it simulates exactly the evaluation's motion and is the fair reference.
(b) the time to build a candidate's world with a 2x3 hand (target < 3 ms), against one
    rollout of that world.
(c) the resident memory growth over many candidate evaluations (target < 50 MB for 10,000).
    These use a 0.05 s rollout: memory is spent building and removing scenes, not stepping.

Usage: python bench/bench_core.py [--quick]    (--quick: fewer candidates, about 1 minute)
"""

import argparse
import dataclasses
import os
import time

from hand_codesign.core.evaluate import evaluate, evaluate_design, shared_simulator
from hand_codesign.core.sim.hand import hand_model
from hand_codesign.core.sim.objectives import goal_schedule
from hand_codesign.core.sim.policies import make_policy
from hand_codesign.core.sim.pybullet_sim import object_shape
from hand_codesign.core.sim.worlds import object_state, world_states
from hand_codesign.core.task import load_task
from hand_codesign.core.task.genome import genome_spec
import numpy as np
import psutil

TASK_FILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'config', 'tasks',
                         'task5.yaml')


def candidates(task, count, seed, sigma=0.1):
    """Return `count` genomes drawn around the mean as CMA-ES starts, simulated in full."""
    spec = genome_spec(task)
    generator = np.random.default_rng(seed)
    chosen = []
    while len(chosen) < count:
        x = spec.initial_mean() + sigma * generator.standard_normal(spec.size)
        result = evaluate(x, task)
        if not result.collision and not result.unstable_worlds:
            chosen.append(x)
    return chosen


def built_candidate(task, x, simulator):
    """Build the candidate's hand in `simulator`; return (model, torque rows, steps)."""
    design = genome_spec(task).decode(x)
    model = hand_model(design.hand, task.hand)
    policy = make_policy(task.policy, design.controller, model.initial_angles, task.time_step)
    steps = simulator.plan(goal_schedule(task)).num_steps
    simulator.build(task, model)
    return model, policy.schedule(steps), steps


def bare_loop(task, x, simulator, with_torques):
    """
    Return the seconds of a bare loop over the candidate's worlds, in a freshly built scene.

    Each world starts as in evaluate() (hand reset, the world's object created, untimed);
    only the stepping is timed: stepSimulation alone, or with the candidate's torques.
    """
    model, rows, steps = built_candidate(task, x, simulator)
    client = simulator.client
    step_simulation = client.stepSimulation
    set_torques = client.setJointMotorControlArray
    joints, hand, torque_control = list(range(model.num_joints)), simulator.hand, \
        client.TORQUE_CONTROL
    elapsed = 0.0
    for world in world_states(task):
        state = object_state(task, world)
        simulator.reset_hand()
        simulator.create_object(state, object_shape(client, state, task.object_spec.shape))
        start = time.process_time()
        if with_torques:
            for step in range(steps):
                set_torques(hand, joints, torque_control, forces=rows[step])
                step_simulation()
        else:
            for _ in range(steps):
                step_simulation()
        elapsed += time.process_time() - start
        simulator.remove_object()
    return elapsed


def torque_calls(task, x, simulator):
    """
    Return the seconds of the bare loop's torque calls alone, without stepping.

    The rollout loop makes two calls into PyBullet per step, this and stepSimulation; this
    says how much of a step is the Python call, the most any loop with fewer calls could gain.
    """
    model, rows, steps = built_candidate(task, x, simulator)
    set_torques = simulator.client.setJointMotorControlArray
    joints, hand = list(range(model.num_joints)), simulator.hand
    torque_control = simulator.client.TORQUE_CONTROL
    start = time.process_time()
    for _ in range(task.num_world_states):
        for step in range(steps):
            set_torques(hand, joints, torque_control, forces=rows[step])
    return time.process_time() - start


def bench_rate(task, count, rounds=3):
    """Print (a): evaluation steps per second against the bare loops."""
    simulator = shared_simulator()
    genomes = candidates(task, count, seed=1)
    evaluate(genomes[0], task)
    timing = np.zeros(3)
    calls = 0.0
    steps = 0
    for x in genomes:
        # Interleaved rounds, and each candidate's fastest round of each loop: the least
        # disturbed by other processes on the machine.
        rounds_timing = np.full(3, np.inf)
        for _ in range(rounds):
            start = time.process_time()
            result = evaluate(x, task)
            elapsed = time.process_time() - start
            rounds_timing = np.minimum(rounds_timing, (elapsed,
                                                       bare_loop(task, x, simulator, False),
                                                       bare_loop(task, x, simulator, True)))
        timing += rounds_timing
        calls += min(torque_calls(task, x, simulator) for _ in range(rounds))
        steps += int(round(result.simulated_time / task.time_step))
    rates = steps / timing
    print(f'(a) evaluation rate, {count} candidates x {task.num_world_states} worlds, '
          f'{steps} steps, best of {rounds} interleaved rounds')
    print(f'    evaluate()            {rates[0]:9.0f} steps/s')
    print(f'    bare, same torques    {rates[2]:9.0f} steps/s   ratio {rates[0] / rates[2]:.3f}'
          '  (target >= 0.90)')
    print(f'    bare, stepping only   {rates[1]:9.0f} steps/s   ratio {rates[0] / rates[1]:.3f}'
          '  (limp hand: other contacts)')
    bare_steps = count * task.num_world_states * simulator.plan(goal_schedule(task)).num_steps
    call, step = calls / bare_steps, timing[2] / bare_steps
    print(f'    torque call alone     {call * 1e6:9.2f} us of {step * 1e6:.2f} us per bare step '
          f'({call / step:.3f}: the most fewer Python calls per step could save)')


def bench_build(task, repeats):
    """Print (b): building the world of a 2x3 hand against one rollout of it."""
    task = task.replace(structure=(2, 3))
    design = genome_spec(task).decode(candidates(task, 1, seed=3)[0])
    simulator = shared_simulator()
    for _ in range(20):
        simulator.build(task, hand_model(design.hand, task.hand))
    start = time.process_time()
    for _ in range(repeats):
        simulator.build(task, hand_model(design.hand, task.hand))
    build = (time.process_time() - start) / repeats
    worlds = world_states(task, 1)
    start = time.process_time()
    for _ in range(5):
        evaluate_design(design, task, worlds)
    candidate = (time.process_time() - start) / 5
    print(f'(b) world build of a 2x3 hand (reset, ground, hand): '
          f'{build * 1e3:.2f} ms  (target < 3 ms)')
    print(f'    reference: one candidate on one world (build, check, rollout, objectives) '
          f'{candidate * 1e3:.1f} ms; build share {build / candidate:.3f}')


def short_task(task, duration=0.05):
    """Return the task with a rollout of `duration` seconds (goal and policy shortened)."""
    goals = dataclasses.replace(
        task.goals,
        position=tuple(dataclasses.replace(goal, time=duration)
                       for goal in task.goals.position[:1]),
        orientation=tuple(dataclasses.replace(goal, time=duration)
                          for goal in task.goals.orientation[:1]))
    policy = dataclasses.replace(task.policy, duration=duration)
    return task.replace(duration=duration, goals=goals, policy=policy)


def bench_memory(task, count):
    """Print (c): RSS growth over `count` candidate evaluations."""
    task = short_task(task)
    spec = genome_spec(task)
    generator = np.random.default_rng(2)
    process = psutil.Process()
    warmup = 200
    collisions = 0
    for index in range(warmup + count):
        if index == warmup:
            rss_start = process.memory_info().rss
            start = time.process_time()
        x = spec.initial_mean() + 0.2 * generator.standard_normal(spec.size)
        collisions += evaluate(x, task).collision
    elapsed = time.process_time() - start
    growth = (process.memory_info().rss - rss_start) / 1e6
    print(f'(c) RSS growth over {count} candidates x {task.num_world_states} worlds '
          f'({collisions} in collision, {elapsed:.0f} s): {growth:.1f} MB  (target < 50 MB; '
          f'RSS after warm-up {rss_start / 1e6:.0f} MB)')


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--quick', action='store_true', help='fewer candidates')
    args = parser.parse_args()
    task = load_task(TASK_FILE)
    bench_rate(task, 8 if args.quick else 40)
    bench_build(task, 200 if args.quick else 1000)
    bench_memory(task, 1000 if args.quick else 10000)


if __name__ == '__main__':
    main()
