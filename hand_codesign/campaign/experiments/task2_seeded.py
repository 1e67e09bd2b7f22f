"""
Task 2 of the paper: turn a sphere by 180 degrees in midair, seeded, CMA-ES with a PD policy.

The paper seeds Task 2 from [7]'s results (not published) and lists them as turns
"clock-/counterclockwise", read here as two runs: task2.yaml (clockwise) and task2_ccw.yaml,
both seeded from a tripod of fingertips that holds the sphere and turns it a little. Beside
them, clockwise from a stand-in that makes most of the turn in the nominal world, as [7]'s
results do (task2_turning.yaml, made by the search in config/stand-ins/).
"""

from hand_codesign.campaign.experiment import budgets
from hand_codesign.campaign.experiment import Configuration
from hand_codesign.campaign.experiment import Experiment
from hand_codesign.campaign.registry import add
from hand_codesign.core.experiments.measures import ORIENTATION_01

WORLDS = 16  # Table I's world states for Task 2


@add
def task2_seeded():
    """Return the experiment: Task 2 clockwise and counter-clockwise, seeded, CMA-ES."""
    return Experiment(
        'task2-seeded',
        'Task 2 (turn a sphere 180 degrees in midair) seeded from the starting hand, clockwise '
        'and counter-clockwise (CMA-ES, PD)',
        (Configuration('task2-seeded-cma-16w', 'task2.yaml', 'cma', WORLDS, 'pd'),
         Configuration('task2-ccw-seeded-cma-16w', 'task2_ccw.yaml', 'cma', WORLDS, 'pd'),
         Configuration('task2-turning-seeded-cma-16w', 'task2_turning.yaml', 'cma', WORLDS,
                       'pd')),
        ORIENTATION_01, budgets((3, 8, 100, 1), (40, 24, 1000, 2), (1000, 250, 1000, 5)))
