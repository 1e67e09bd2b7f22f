"""
How much of a MuJoCo evaluation is MuJoCo's own step: the floor under a run's wall time.

An open-loop torque policy (Tasks 4 to 6) is stepped in C by mj_step from one torque change or
event to the next (core.sim.mujoco_sim). What Python adds around it (the world's build and
reset, the events' checks, the objectives) is all that code of ours can still remove; the
step itself (contacts, constraint solver, integration) only cheaper physics settings can.

Measures, per task, on simulated designs spread over a short seeded CMA-ES search in MuJoCo
(--generations x --population on --world-states worlds), each evaluated again on the same
worlds: the CPU seconds of evaluate() against the CPU seconds spent inside mujoco.mj_step in
the same calls (the reference, measured in the same run). The ratio step / evaluate is the
share no change of ours outside MuJoCo can remove: a Table I run's wall time times that share
is its floor at these physics settings.

Usage: python bench/bench_mujoco_floor.py [--tasks task5 task4_structure] [--designs 12]
           [--generations 6] [--population 16] [--world-states 64] [--rounds 2]
"""

import argparse
import os
import time

from bench_engines import on_engine
from bench_physics import searched_designs
from hand_codesign.core.evaluate import evaluate
from hand_codesign.core.task import load_task
import mujoco

CONFIG = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'config')


def task_file(name):
    """Return the path of a task named by its file's stem (config/tasks, then config/reproduce)."""
    for folder in ('tasks', 'reproduce'):
        path = os.path.join(CONFIG, folder, f'{name}.yaml')
        if os.path.exists(path):
            return path
    raise SystemExit(f'bench_mujoco_floor: no config/tasks/{name}.yaml or '
                     f'config/reproduce/{name}.yaml')


class StepClock:
    """Wraps mujoco.mj_step while in use; `seconds` is the CPU time spent inside it."""

    def __init__(self):
        self.seconds = 0.0
        self._step = mujoco.mj_step

    def _timed(self, *args):
        start = time.process_time()
        self._step(*args)
        self.seconds += time.process_time() - start

    def __enter__(self):
        mujoco.mj_step = self._timed
        return self

    def __exit__(self, *exc_info):
        mujoco.mj_step = self._step


def floor_share(task, genomes, rounds):
    """Return (evaluate seconds, mj_step seconds) per round's genomes, best round by evaluate."""
    best = None
    for _ in range(rounds):
        with StepClock() as clock:
            start = time.process_time()
            for x in genomes:
                evaluate(x, task)
            seconds = time.process_time() - start
        if best is None or seconds < best[0]:
            best = (seconds, clock.seconds)
    return best


def main():
    """Print, per task, evaluate()'s CPU time, the time inside mj_step and their ratio."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--tasks', nargs='+', default=['task5', 'task4_structure'],
                        help='task file stems (default task5 task4_structure)')
    parser.add_argument('--designs', type=int, default=12, help='designs timed (default 12)')
    parser.add_argument('--generations', type=int, default=6,
                        help='generations of the search the designs come from (default 6)')
    parser.add_argument('--population', type=int, default=16,
                        help='its population (default 16)')
    parser.add_argument('--world-states', type=int, default=64,
                        help='worlds per evaluation (default 64, Table I)')
    parser.add_argument('--rounds', type=int, default=2, help='best of (default 2)')
    arguments = parser.parse_args()
    paths = [task_file(name) for name in arguments.tasks]
    print(f'{"task":<18} {"designs":>7} {"evaluate s":>10} {"mj_step s":>10} '
          f'{"step share":>10}')
    for name, path in zip(arguments.tasks, paths):
        task = load_task(path).replace(
            num_world_states=arguments.world_states, population=arguments.population, seed=1,
            iterations=10 ** 6)
        task = on_engine(task, 'mujoco')
        genomes, _ = searched_designs(task, arguments.generations, arguments.designs)
        seconds, stepping = floor_share(task, genomes, arguments.rounds)
        if stepping == 0:  # the simulator no longer looks mj_step up at each rollout
            raise SystemExit('bench_mujoco_floor: no time was seen inside mujoco.mj_step')
        print(f'{name:<18} {len(genomes):>7} {seconds:>10.2f} {stepping:>10.2f} '
              f'{stepping / seconds:>10.3f}')


if __name__ == '__main__':
    main()
