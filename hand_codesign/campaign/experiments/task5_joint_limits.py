"""
Task 5 of the paper: align a box on the plane with the fixed 2x2 hand; joint limits found.

CMA-ES and MO-CMA-ES on 8, 64 and 128 worlds, with the torque and the PD policy. Task 5 keeps
the hand above the box (`task5.yaml`), which the tuning of the palm's reading kept (Task 6's
experiment turned to the palm beside the box).
"""

from hand_codesign.campaign.experiment import budgets
from hand_codesign.campaign.experiment import Experiment
from hand_codesign.campaign.registry import add
from hand_codesign.campaign.shared import joint_limit_configurations
from hand_codesign.core.experiments.measures import ALONG_X_5MM
from hand_codesign.core.experiments.measures import ALONG_Y_5MM
from hand_codesign.core.experiments.measures import PLANE_5MM


@add
def task5_joint_limits():
    """Return the experiment: the paper's grid on Task 5, within 5 mm in the plane."""
    return Experiment(
        'task5-joint-limits',
        'Task 5 (align a box on the plane, fixed 2x2 hand): CMA-ES and MO-CMA-ES on 8, 64 and '
        '128 worlds, torque and PD policies; joint limits found',
        joint_limit_configurations('task5.yaml', 'task5', ('torque', 'pd')), PLANE_5MM,
        budgets((4, 8, 100, 1), (16, 16, 1000, 2), (100, 80, 1000, 5)),
        also=(ALONG_X_5MM, ALONG_Y_5MM))
