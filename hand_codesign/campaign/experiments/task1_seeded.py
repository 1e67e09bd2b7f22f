"""
Fig. 2 of the paper: Task 1 seeded from the starting hand against Task 3 from scratch.

CMA-ES on Task 1 (PD, and the torque variant) and MO-CMA-ES on Task 3 (torques), their
convergence drawn side by side. Beside them, Task 1 seeded from a stand-in that already turns
the capsule in the nominal world, as [7]'s results do (task1_turning.yaml, made by the search
in config/stand-ins/task1_stand_in_search.yaml, and task1_turning_800.yaml from the same search
run longer, and task1_turning_800_dense.yaml: the same with segments ten times as dense); the
pinned task1.yaml's stand-in leaves the whole turn to the search.
"""

from hand_codesign.campaign.experiment import budgets
from hand_codesign.campaign.experiment import Configuration
from hand_codesign.campaign.experiment import Experiment
from hand_codesign.campaign.registry import add
from hand_codesign.core.experiments.measures import ORIENTATION_01


@add
def task1_seeded():
    """Return the experiment: seeded against from scratch, convergence side by side."""
    return Experiment(
        'task1-seeded',
        'Task 1 seeded from the starting hand (CMA-ES; PD, and the torque variant) against '
        'Task 3 from scratch (MO-CMA-ES, torques): convergence side by side (Fig. 2)',
        (Configuration('task1-seeded-cma-16w', 'task1.yaml', 'cma', 16, 'pd'),
         Configuration('task1-seeded-torque-cma-16w', 'task1_torque.yaml', 'cma', 16,
                       'torque'),
         Configuration('task3-scratch-mocma-16w', 'task3.yaml', 'mocma', 16, 'torque'),
         Configuration('task1-turning-seeded-cma-16w', 'task1_turning.yaml', 'cma', 16, 'pd'),
         Configuration('task1-turning800-seeded-cma-16w', 'task1_turning_800.yaml', 'cma', 16,
                       'pd'),
         Configuration('task1-turning800-dense-seeded-cma-16w', 'task1_turning_800_dense.yaml',
                       'cma', 16, 'pd')),
        ORIENTATION_01, budgets((3, 8, 100, 1), (40, 24, 1000, 2), (1000, 250, 1000, 5)),
        convergence=True)
