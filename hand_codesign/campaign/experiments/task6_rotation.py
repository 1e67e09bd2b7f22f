"""
Task 6 of the paper: turn a box 45 degrees on the plane with the fixed 2x2 hand.

CMA-ES and MO-CMA-ES on 8, 64 and 128 worlds, torque policy. It runs the fixed hand read with
the palm beside the box (`task6_palm_beside.yaml`), chosen on tuning seeds 1 to 3 over the
hand above it (`task6.yaml`, which the levers' campaigns ran).
"""

from hand_codesign.campaign.experiment import budgets
from hand_codesign.campaign.experiment import Experiment
from hand_codesign.campaign.registry import add
from hand_codesign.campaign.shared import joint_limit_configurations
from hand_codesign.core.experiments.measures import ORIENTATION_01


@add
def task6_rotation():
    """Return the experiment: the paper's grid on Task 6, within 0.1 rad."""
    return Experiment(
        'task6-rotation',
        'Task 6 (turn a box 45 degrees on the plane, fixed 2x2 hand): CMA-ES and MO-CMA-ES on '
        '8, 64 and 128 worlds; joint limits found',
        joint_limit_configurations('task6_palm_beside.yaml', 'task6', ('torque',)),
        ORIENTATION_01,
        budgets((4, 8, 100, 1), (25, 16, 1000, 2), (100, 80, 1000, 5)))
