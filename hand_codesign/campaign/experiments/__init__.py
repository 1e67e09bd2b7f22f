"""
The experiments `hand-codesign reproduce` runs, one module each, registered by name.

Each module adds its Experiment to the registry (hand_codesign.campaign.registry); this face
imports them in the order `reproduce --list` shows and `reproduce all` runs the paper's:
Tasks 5 and 6 (joint limits found), Task 4's hierarchy (Fig. 3), Task 1 seeded (Fig. 2), Task 2
seeded, then the experiments `all` leaves out: Task 4's structures one at a time, Task 3's
levers, the levers of Tasks 5 and 6. A new experiment is a new module, imported below; a new
lever is a change to one experiment's module.
"""

from typing import Dict, List

from hand_codesign.campaign.experiment import Experiment
from hand_codesign.campaign.experiments import levers_task5
from hand_codesign.campaign.experiments import levers_task6
from hand_codesign.campaign.experiments import task1_seeded
from hand_codesign.campaign.experiments import task2_seeded
from hand_codesign.campaign.experiments import task3_levers
from hand_codesign.campaign.experiments import task4_hierarchy
from hand_codesign.campaign.experiments import task4_structures
from hand_codesign.campaign.experiments import task5_joint_limits
from hand_codesign.campaign.experiments import task6_rotation
from hand_codesign.campaign.registry import added

# imported for what they register, in this order (the order of `reproduce --list`)
MODULES = (task5_joint_limits, task6_rotation, task4_hierarchy, task1_seeded, task2_seeded,
           task4_structures, task3_levers, levers_task5, levers_task6)
EXPERIMENTS: Dict[str, Experiment] = {
    experiment.name: experiment
    for experiment in (added()[module.__name__] for module in MODULES)}
ALL = 'all'


def experiment_names() -> List[str]:
    """
    Return the experiment names `reproduce` accepts, `all` last.

    Returns:
        list of names, in registration order, then ALL.
    """
    return list(EXPERIMENTS) + [ALL]


def paper_experiments() -> List[Experiment]:
    """
    Return the experiments of the paper (those `all` runs), in order.

    Returns:
        list of Experiment, those not beyond the paper.
    """
    return [experiment for experiment in EXPERIMENTS.values() if not experiment.beyond_paper]


__all__ = ['ALL', 'EXPERIMENTS', 'experiment_names', 'MODULES', 'paper_experiments']
