"""
Task 4 of the paper: the structure hierarchy (Fig. 1), each structure measured (Fig. 3).

MO-CMA-ES over the hierarchy of structures; every structure's best design is measured on
unseen worlds besides the run's result, against the pose tolerance (the box turned and kept
in place at once).
"""

from hand_codesign.campaign.experiment import budgets
from hand_codesign.campaign.experiment import Configuration
from hand_codesign.campaign.experiment import Experiment
from hand_codesign.campaign.registry import add
from hand_codesign.core.experiments.measures import ORIENTATION_01
from hand_codesign.core.experiments.measures import PLANE_5MM
from hand_codesign.core.experiments.measures import POSE


@add
def task4_hierarchy():
    """Return the experiment: the hierarchy on Task 4, each structure's best measured."""
    return Experiment(
        'task4-hierarchy',
        'Task 4 (turn a box 45 degrees, keep its position): the structure hierarchy with '
        'MO-CMA-ES, each structure measured on unseen worlds (Fig. 3)',
        (Configuration('hierarchy-mocma-64w', 'task4.yaml', 'mocma', 64, 'torque'),),
        POSE, budgets((2, 8, 100, 1), (20, 16, 1000, 2), (200, 150, 1000, 2)),
        per_structure=True, also=(ORIENTATION_01, PLANE_5MM))
