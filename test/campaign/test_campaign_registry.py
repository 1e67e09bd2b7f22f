"""The experiments' registry: one module per experiment, each registered by name, in order."""

import pkgutil

from hand_codesign.campaign import experiments
from hand_codesign.campaign import registry
from hand_codesign.campaign.experiment import Experiment
from hand_codesign.core.experiments.measures import PLANE_5MM
import pytest


def test_every_module_of_the_experiments_registers_one_listed_experiment():
    found = {f'{experiments.__name__}.{module.name}'
             for module in pkgutil.iter_modules(experiments.__path__)}
    listed = [module.__name__ for module in experiments.MODULES]
    assert sorted(listed) == sorted(found)
    added = registry.added()
    assert [added[name].name for name in listed] == list(experiments.EXPERIMENTS)


def test_reproduce_lists_the_papers_experiments_first_and_all_runs_those():
    assert experiments.experiment_names() == [
        'task5-joint-limits', 'task6-rotation', 'task4-hierarchy', 'task1-seeded',
        'task2-seeded', 'task4-structures', 'task3-levers', 'levers-task5', 'levers-task6',
        'all']
    assert [experiment.name for experiment in experiments.paper_experiments()] == [
        'task5-joint-limits', 'task6-rotation', 'task4-hierarchy', 'task1-seeded',
        'task2-seeded']


def test_each_module_builds_the_experiment_registered_under_its_name():
    # what a module's function returns is what `reproduce` runs: a lever added to it is there
    for module in experiments.MODULES:
        builder = getattr(module, module.__name__.rpartition('.')[2])
        assert builder() == experiments.EXPERIMENTS[builder().name]


def test_a_name_is_registered_once_and_a_module_adds_one_experiment():
    def twin():
        return Experiment('task5-joint-limits', '', (), PLANE_5MM, {})

    with pytest.raises(ValueError, match='registered already'):
        registry.add(twin)
    with pytest.raises(ValueError, match='one module holds one'):
        registry.add(experiments.task1_seeded.task1_seeded)
