"""A decoded candidate in physical units: structure, joints, and equality by value."""

import pathlib

from hand_codesign.core.design import ControllerDesign
from hand_codesign.core.design import Design
from hand_codesign.core.run.runs import load_run_task
from hand_codesign.core.task.genome import genome_spec
import numpy as np

TASK = pathlib.Path(__file__).resolve().parents[2] / 'config' / 'tasks' / 'task5.yaml'


def test_a_decoded_design_has_the_task_structure_within_its_bounds():
    task = load_run_task(TASK, 1, 1, 4, 2)
    spec = genome_spec(task)
    design = spec.decode(np.full(spec.size, 0.5))
    assert isinstance(design, Design)
    assert design.hand.structure == task.structure
    assert design.hand.num_joints == sum(task.structure)
    for finger in design.hand.fingers:
        assert len(finger.segment_lengths) == len(finger.joints)
        assert all(length > 0 for length in finger.segment_lengths)
        for joint in finger.joints:
            if joint.lower_limit is not None:
                assert joint.lower_limit <= joint.initial_angle <= joint.upper_limit
    assert design.controller.values.shape[-1] == design.hand.num_joints


def test_controllers_compare_and_hash_by_value():
    one = ControllerDesign('pd', np.array([[0.1, 0.2]]), np.array([1.0, 2.0]),
                           np.array([0.1, 0.1]))
    same = ControllerDesign('pd', np.array([[0.1, 0.2]]), np.array([1.0, 2.0]),
                            np.array([0.1, 0.1]))
    other = ControllerDesign('pd', np.array([[0.1, 0.3]]), np.array([1.0, 2.0]),
                             np.array([0.1, 0.1]))
    assert one == same and hash(one) == hash(same)
    assert one != other
    assert ControllerDesign('torque', np.array([[0.1, 0.2]])) != one
    assert len({one, same, other}) == 2


def test_different_genomes_give_different_designs():
    task = load_run_task(TASK, 1, 1, 4, 2)
    spec = genome_spec(task)
    assert spec.decode(np.full(spec.size, 0.4)) != spec.decode(np.full(spec.size, 0.6))
    assert spec.decode(np.full(spec.size, 0.4)) == spec.decode(np.full(spec.size, 0.4))
