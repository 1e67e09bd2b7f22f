"""
The workload that PyBullet's profile-guided build (tools/build_pybullet.py) is trained on.

A co-design's evaluations, small: designs drawn around the search's start on the presets of
Tasks 5 (box pushed on the plane, torque and PD), 6 (box turned) and 1 (capsule turned in
midair, seeded, PD), so that the profile sees the contact, friction, joint-limit and motor
rows of the solver and the collision pairs of boxes, capsules and finger capsules in the
proportions a run meets them. The profile only steers where the compiler lays out and inlines
code; a task not in it runs correctly, at most less fast.

Usage: python tools/physics_workload.py    (about 30 s when instrumented)
"""

import pathlib

from hand_codesign.core.evaluate import evaluate
from hand_codesign.core.task import load_task
from hand_codesign.core.task.genome import genome_spec
import numpy as np

TASKS = pathlib.Path(__file__).resolve().parents[1] / 'config' / 'tasks'
PRESETS = ('task5.yaml', 'task5_pd.yaml', 'task6.yaml', 'task1.yaml')
DESIGNS_PER_TASK = 10
WORLDS = 8
SIGMA = 0.1  # the search's initial step size in the normalized genome space


def run_workload():
    """Evaluate a few designs of each preset; return the physics steps simulated."""
    steps = 0
    generator = np.random.default_rng(0)
    for preset in PRESETS:
        task = load_task(TASKS / preset).replace(num_world_states=WORLDS)
        spec = genome_spec(task)
        for _ in range(DESIGNS_PER_TASK):
            x = spec.initial_mean() + SIGMA * generator.standard_normal(spec.size)
            steps += round(evaluate(x, task).simulated_time / task.time_step)
    return steps


if __name__ == '__main__':
    print(f'physics workload: {run_workload()} steps')
