"""Task 4's presets read Table I's shared cells: the joint limits are optimized in [-pi, pi]."""

import json
import math
import pathlib

from analysis_run import run_codesign
from hand_codesign.core.task import load_task
from hand_codesign.core.task.genome import genome_spec
import pytest

CONFIG = pathlib.Path(__file__).resolve().parents[3] / 'config'
PAPER = ('tasks/task4.yaml', 'tasks/task4_extended.yaml', 'reproduce/task4.yaml',
         'reproduce/task4_structure.yaml')
FREE = ('tasks/task4_free_joints.yaml', 'tasks/task4_extended_free_joints.yaml')


def limit_genes(task):
    """Return {gene name: (low, high)} of a task's joint-limit genes (its first structure)."""
    spec = genome_spec(task)
    return {name: (low, high) for name, low, high in zip(spec.names, spec.lower, spec.upper)
            if name.endswith(('.lower_limit', '.upper_limit'))}


@pytest.mark.parametrize('name', PAPER)
def test_the_paper_presets_optimize_every_joint_limit_within_minus_pi_to_pi(name):
    task = load_task(CONFIG / name)
    genes = limit_genes(task)
    joints = sum(task.structure or task.hierarchy.start)
    assert len(genes) == 2 * joints
    assert set(genes.values()) == {(-math.pi, math.pi)}


@pytest.mark.parametrize('name', FREE)
def test_the_named_variants_keep_the_earlier_reading_free_joints(name):
    task = load_task(CONFIG / name)
    assert task.name.endswith('free_joints') and not limit_genes(task)


@pytest.mark.system
def test_a_real_run_of_the_extended_preset_returns_a_hand_with_limits(tmp_path):
    bag = tmp_path / 'task4'
    run_codesign(bag, ['--iterations', '2', '--population', '4', '--world-states', '2',
                       '--seed', '3'], task=CONFIG / 'tasks' / 'task4_extended.yaml')
    design = json.loads((bag / 'result.json').read_text())['design']
    for finger, joints in enumerate((1, 3)):
        for joint in range(joints):
            prefix = f'finger{finger}.joint{joint}.'
            lower, upper = design[prefix + 'lower_limit'], design[prefix + 'upper_limit']
            assert -math.pi <= lower <= upper <= math.pi
            assert lower <= design[prefix + 'initial_angle'] <= upper
