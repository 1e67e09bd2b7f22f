"""
Benchmark: a candidate's open-loop worlds in mujoco's batch module against today's MuJoCo path.

Today's path (core.sim.mujoco_sim) runs a candidate's worlds one after the other on one MjData,
each stepped in C (mj_step's nstep) from one torque change or event to the next. MuJoCo 4.0's
mujoco.batch.Batch runs all the worlds of a candidate at once, one model per world (the world
written into a copy of the candidate's compiled model, as today's path writes it), on C
threads: here either in one `Batch.rollout` call over the whole horizon (torques per substep,
early termination and checks left to the recorded states), or in one call per chunk between
the events of core.sim.events (where early termination could drop worlds).

Measures, in one run, on --designs designs around the search's start of each task that do not
start in collision, at --world-states worlds:
- whether each batch variant ends every world in the same state as today's stepping loop, bit
  for bit, with 1 and 2 threads (the batch's promise: a loop over one MjData per world);
- CPU seconds per candidate (this process, all threads), best of --rounds: today's evaluate(),
  its bare stepping loop (torques and steps only), and each batch variant with 1 and 2
  threads, as ratios to evaluate(). A run has two evaluators on the two cores, so per core is
  what counts; with 2 threads also the wall time of one candidate (what a single evaluator
  would gain on an idle machine).

Usage: python bench/bench_mujoco_batch.py [--tasks task5 task6] [--world-states 8 64]
       [--designs 4] [--rounds 3]
"""

import argparse
import copy
import dataclasses
import os
import time

from hand_codesign.core.evaluate import evaluate
from hand_codesign.core.sim.hand import hand_model
from hand_codesign.core.sim.mujoco_sim import MujocoSimulator
from hand_codesign.core.sim.objectives import goal_schedule
from hand_codesign.core.sim.policies import make_policy
from hand_codesign.core.sim.worlds import object_state, world_states
from hand_codesign.core.task import load_task
from hand_codesign.core.task.genome import genome_spec
import mujoco
from mujoco import batch as mujoco_batch
import numpy as np

TASKS = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'config', 'tasks')
APPLIED = mujoco.mjtState.mjSTATE_QFRC_APPLIED.value


class Candidate:
    """One design's compiled worlds (a model each), its torques and the loop's events."""

    def __init__(self, task, x):
        design = genome_spec(task).decode(x)
        self.model = hand_model(design.hand, task.hand)
        self.policy = make_policy(task.policy, design.controller, self.model.initial_angles,
                                  task.time_step)
        self.simulator = MujocoSimulator()
        self.simulator.build(task, self.model)
        self.plan = self.simulator.plan(goal_schedule(task))
        self.states = [object_state(task, world) for world in world_states(task)]
        self.shape = task.object_spec.shape
        m = self.simulator.mj_model
        rows = np.array(self.policy.schedule(self.plan.num_steps))
        self.control = np.zeros((self.plan.num_steps, m.nv))
        self.control[:, :self.model.num_joints] = rows

    def world_models(self):
        """Return a copy of the compiled model per world, the world written into it."""
        models = []
        for state in self.states:
            self.simulator.reset(state, self.shape)
            models.append(copy.copy(self.simulator.mj_model))
        return models

    def loop(self):
        """Return the final qpos of every world, stepped as today's path steps them."""
        simulator, joints, finals = self.simulator, self.model.num_joints, []
        for state in self.states:
            simulator.reset(state, self.shape)
            m, d = simulator.mj_model, simulator.mj_data
            done = 0
            for stop in [*self.plan.steps[:-1], self.plan.num_steps]:
                while done < stop:
                    d.qfrc_applied[:joints] = self.control[done, :joints]
                    mujoco.mj_step(m, d)
                    done += 1
            finals.append(d.qpos.copy())
        return np.array(finals)

    def batch(self, threads, chunked):
        """Return the final qpos of every world, stepped in one Batch of `threads` threads."""
        models = self.world_models()
        batch = mujoco_batch.Batch(models[0], len(models), threads)
        batch.set_models(models)
        batch.reset(stage=mujoco.mjtStage.mjSTAGE_NONE.value)
        qpos = batch.bind('qpos')
        qpos[:, :self.model.num_joints] = self.model.initial_angles
        stops = [*self.plan.steps[:-1], self.plan.num_steps] if chunked else [
            self.plan.num_steps]
        done = 0
        for stop in stops:
            if stop > done:
                batch.rollout(stop - done, self.control[None, done:stop], APPLIED,
                              record=('qpos',))
                done = stop
        return qpos.copy()


def designs(task, count, seed=1):
    """Return `count` genomes around the search's start that do not start in collision."""
    spec = genome_spec(task)
    generator = np.random.default_rng(seed)
    found = []
    while len(found) < count:
        x = np.clip(spec.initial_mean() + 0.1 * generator.normal(size=spec.size), 0, 1)
        if not evaluate(x, task).collision:
            found.append(x)
    return found


def best_seconds(work, genomes, rounds, clock=time.process_time):
    """Return the seconds per genome of work(x), best of rounds."""
    best = np.inf
    for _ in range(rounds):
        start = clock()
        for x in genomes:
            work(x)
        best = min(best, clock() - start)
    return best / len(genomes)


def bench(name, worlds, arguments):
    """Print the figures of one task at one number of worlds."""
    task = load_task(os.path.join(TASKS, name + '.yaml')).replace(num_world_states=worlds)
    task = task.replace(physics=dataclasses.replace(task.physics, engine='mujoco'))
    genomes = designs(task, arguments.designs)
    reference = Candidate(task, genomes[0]).loop()
    variants = {f'{kind}, {threads} thread{"s" if threads > 1 else ""}': (threads, chunked)
                for kind, chunked in (('one rollout call', False), ('calls per chunk', True))
                for threads in (1, 2)}
    same = {label: np.array_equal(Candidate(task, genomes[0]).batch(*variant), reference)
            for label, variant in variants.items()}
    today = best_seconds(lambda x: evaluate(x, task), genomes, arguments.rounds)
    bare = best_seconds(lambda x: Candidate(task, x).loop(), genomes, arguments.rounds)
    print(f'{name}, {worlds} worlds, {len(genomes)} designs: evaluate() {today * 1e3:.1f} ms '
          f'CPU per candidate; its bare stepping loop {today / bare:.2f} times as fast')
    for label, variant in variants.items():
        cpu = best_seconds(lambda x: Candidate(task, x).batch(*variant), genomes,
                           arguments.rounds)
        wall = best_seconds(lambda x: Candidate(task, x).batch(*variant), genomes,
                            arguments.rounds, time.perf_counter)
        print(f'  batch, {label}: {today / cpu:.2f} times as fast per core as evaluate() '
              f'({cpu * 1e3:.1f} ms CPU, {wall * 1e3:.1f} ms wall); same bits as the loop: '
              f'{"yes" if same[label] else "NO"}')


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--tasks', nargs='+', default=['task5', 'task6'])
    parser.add_argument('--world-states', nargs='+', type=int, default=[8, 64])
    parser.add_argument('--designs', type=int, default=4)
    parser.add_argument('--rounds', type=int, default=3)
    arguments = parser.parse_args()
    for name in arguments.tasks:
        for worlds in arguments.world_states:
            bench(name, worlds, arguments)


if __name__ == '__main__':
    main()
