"""Genome: named genes with the task's bounds, a continuous mapping, and Design round trips."""

import dataclasses
import math
import pathlib

from hand_codesign.core import (decode, genome_spec, load_task, objective_names, parse_task,
                                TaskError)
from hand_codesign.core.search.factory import make_optimizer
from hand_codesign.core.task.genome import fold, seed_genome
import numpy as np
import pytest

TASKS = pathlib.Path(__file__).resolve().parents[3] / 'config' / 'tasks'
PRESETS = sorted(path.stem for path in TASKS.glob('*.yaml'))


def numbers(design):
    """Return every number of a Design in a flat list (nan for absent limits)."""
    values = [design.hand.friction]
    for finger in design.hand.fingers:
        values += list(finger.position) + list(finger.segment_lengths)
        for joint in finger.joints:
            values += [joint.axis_angle, joint.initial_angle,
                       math.nan if joint.lower_limit is None else joint.lower_limit,
                       math.nan if joint.upper_limit is None else joint.upper_limit]
    controller = design.controller
    for array in (controller.values, controller.kp, controller.kd):
        values += [] if array is None else list(np.ravel(array))
    return values


def assert_same_design(first, second):
    assert first.hand.structure == second.hand.structure
    assert first.controller.kind == second.controller.kind
    assert numbers(first) == pytest.approx(numbers(second), abs=1e-12, nan_ok=True)


def test_fold_is_continuous_identity_on_unit_interval():
    x = np.linspace(0.0, 1.0, 11)
    assert fold(x) == pytest.approx(x)
    assert fold([-0.25, 1.25, 2.25, -1.75, 3.0]) == pytest.approx([0.25, 0.75, 0.25, 0.25, 1.0])
    dense = np.linspace(-5.0, 5.0, 100001)
    assert np.abs(np.diff(fold(dense))).max() <= (dense[1] - dense[0]) + 1e-12
    assert ((fold(dense) >= 0) & (fold(dense) <= 1)).all()


def test_task5_genes_and_bounds():
    spec = genome_spec(load_task(TASKS / 'task5.yaml'))
    assert spec.size == len(spec.names) == len(set(spec.names)) == 24
    assert 'finger0.segment1.length' in spec.names
    assert 'finger1.joint0.lower_limit' in spec.names
    assert 'controller.torque.k1.finger1.joint1' in spec.names
    assert 'finger0.position_x' not in spec.names  # fixed in Task 5
    index = spec.index('finger0.segment1.length')
    assert (spec.lower[index], spec.upper[index]) == (0.04, 0.09)
    assert list(spec.indices('controller.')) == list(range(16, 24))


def test_initial_mean_decodes_to_the_centre_of_the_bounds():
    task = load_task(TASKS / 'task5.yaml')
    spec = genome_spec(task)
    assert (spec.initial_mean() == 0.5).all()
    design = spec.decode(spec.initial_mean())
    assert design.hand.structure == (2, 2)
    finger = design.hand.fingers[1]
    assert finger.position == (0.07, 0.0)
    assert finger.segment_lengths == pytest.approx((0.065, 0.065))
    assert finger.joints[0].axis_angle == pytest.approx(math.pi / 2)
    assert design.hand.friction == 0.8
    assert design.controller.kind == 'torque' and design.controller.values.shape == (2, 4)
    assert np.abs(design.controller.values).max() == pytest.approx(0.0)


@pytest.mark.parametrize('name', PRESETS)
def test_any_genome_decodes_into_bounds(name):
    task = load_task(TASKS / f'{name}.yaml')
    spec = genome_spec(task)
    generator = np.random.default_rng(7)
    for x in generator.normal(0.5, 2.0, size=(20, spec.size)):
        values = np.array(list(spec.values(x).values()))
        assert ((values >= spec.lower - 1e-12) & (values <= spec.upper + 1e-12)).all()
        design = spec.decode(x)
        for finger in design.hand.fingers:
            assert all(length > 0 for length in finger.segment_lengths)
            for joint in finger.joints:
                if joint.lower_limit is not None:
                    assert joint.lower_limit <= joint.initial_angle <= joint.upper_limit
        assert design.hand.friction >= 0


def test_decode_is_continuous_across_a_bound():
    spec = genome_spec(load_task(TASKS / 'task5.yaml'))
    index = spec.index('finger0.segment0.length')
    inside, outside = spec.initial_mean(), spec.initial_mean()
    inside[index], outside[index] = 1.0 - 1e-6, 1.0 + 1e-6
    near = spec.decode(inside).hand.fingers[0].segment_lengths[0]
    across = spec.decode(outside).hand.fingers[0].segment_lengths[0]
    assert near == pytest.approx(across, abs=1e-6) and across <= 0.09


@pytest.mark.parametrize('name', PRESETS)
def test_round_trip(name):
    task = load_task(TASKS / f'{name}.yaml')
    spec = genome_spec(task)
    for x in np.random.default_rng(3).uniform(-1.0, 2.0, size=(10, spec.size)):
        design = spec.decode(x)
        again = spec.encode(design)
        # an initial angle clipped into limits outside its own bounds has no genome
        if ((again >= -1e-9) & (again <= 1 + 1e-9)).all():
            assert_same_design(spec.decode(again), design)
    mean = spec.initial_mean()
    assert spec.encode(spec.decode(mean)) == pytest.approx(mean)
    assert spec.encode(spec.values(mean)) == pytest.approx(mean)


def test_design_values_show_sorted_limits_that_hold_the_initial_angle():
    spec = genome_spec(load_task(TASKS / 'task5.yaml'))
    for x in np.random.default_rng(5).uniform(-1.0, 2.0, size=(10, spec.size)):
        values = spec.design_values(x)
        for finger in range(2):
            for joint in range(2):
                prefix = f'finger{finger}.joint{joint}.'
                lower, upper = values[prefix + 'lower_limit'], values[prefix + 'upper_limit']
                assert lower <= values[prefix + 'initial_angle'] <= upper


def test_joint_limits_are_sorted_and_hold_the_initial_angle():
    spec = genome_spec(load_task(TASKS / 'task5.yaml'))
    x = spec.initial_mean()
    x[spec.index('finger0.joint0.lower_limit')] = 0.9  # lower gene above the upper gene
    x[spec.index('finger0.joint0.upper_limit')] = 0.6
    x[spec.index('finger0.joint0.initial_angle')] = 0.0  # -pi/2: outside the limits
    joint = spec.decode(x).hand.fingers[0].joints[0]
    assert joint.lower_limit == pytest.approx(0.2 * math.pi / 2)
    assert joint.upper_limit == pytest.approx(0.8 * math.pi / 2)
    assert joint.initial_angle == pytest.approx(joint.lower_limit)


def test_fixed_settings_per_finger_and_joint():
    text = (TASKS / 'task5.yaml').read_text()
    text = text.replace('joint_limits: {bounds: [-pi/2, pi/2]}',
                        'joint_limits: {fixed: [[-1, 1], [-0.5, pi/4]]}')
    text = text.replace('initial_angle: {bounds: [-pi/2, pi/2]}',
                        'initial_angle: {fixed: [[0.1, 0.2], 0.3]}')
    task = parse_task(text, source='fixed.yaml')
    spec = genome_spec(task)
    assert spec.size == 12  # segment lengths and torques only
    fingers = spec.decode(spec.initial_mean()).hand.fingers
    assert [j.initial_angle for f in fingers for j in f.joints] == [0.1, 0.2, 0.3, 0.3]
    assert (fingers[1].joints[1].lower_limit, fingers[1].joints[1].upper_limit) == (
        -0.5, pytest.approx(math.pi / 4))
    assert (fingers[0].joints[0].lower_limit, fingers[0].joints[0].upper_limit) == (-1, 1)
    bad = text.replace('initial_angle: {fixed: [[0.1, 0.2], 0.3]}',
                       'initial_angle: {fixed: [[0.1, 0.2, 0.3], 0.3]}')
    with pytest.raises(TaskError, match=r'fixed.yaml: morphology.initial_angle: expected 2 '
                                        r'values for finger 0'):
        parse_task(bad, source='fixed.yaml')


def test_segment_bounds_per_finger_are_divided_by_its_joints():
    task = load_task(TASKS / 'task4.yaml').replace(structure=(1, 3))
    spec = genome_spec(task)
    single, triple = spec.index('finger0.segment0.length'), spec.index('finger1.segment2.length')
    assert (spec.lower[single], spec.upper[single]) == pytest.approx((0.03, 0.10))
    assert (spec.lower[triple], spec.upper[triple]) == pytest.approx((0.01, 0.10 / 3))
    finger1 = spec.index('finger1.position_x')
    assert (spec.lower[finger1], spec.upper[finger1]) == (0.01, 0.07)


def test_seeded_search_centres_on_the_seed():
    task = load_task(TASKS / 'task1.yaml')
    spec = genome_spec(task)
    seed = task.seed_design
    x = seed_genome(task)
    assert_same_design(spec.decode(x), seed)
    friction = spec.index('hand.friction')  # delta [-0.3, 0.1]: the seed sits at 0.75
    assert x[friction] == pytest.approx(0.75)
    others = np.delete(x, [friction] + list(spec.indices('controller.k')))
    assert others == pytest.approx(0.5)
    index = spec.index('finger2.segment1.length')
    assert (spec.lower[index], spec.upper[index]) == pytest.approx((0.30, 0.40))
    target = spec.index('controller.target.k2.finger0.joint0')
    assert (spec.lower[target], spec.upper[target]) == pytest.approx((-1.2, -0.6))
    mean = spec.decode(spec.initial_mean())
    assert mean.hand.friction == pytest.approx(0.9)
    assert mean.controller.kp == pytest.approx(np.full(6, 2550.0))


def test_torque_variant_takes_the_hand_from_the_seed_and_the_torques_from_the_centre():
    """task1_torque.yaml's seed is a PD design: its target angles are no torques."""
    task = load_task(TASKS / 'task1_torque.yaml')
    spec = genome_spec(task)
    x = seed_genome(task)
    torques = spec.indices('controller.torque.')
    assert len(torques) == 18 and (x[torques] == 0.5).all()
    start = spec.decode(x)
    assert np.abs(start.controller.values).max() == pytest.approx(0.0)  # centre of [-0.5, 0.5]
    seed = task.seed_design
    assert_same_design(dataclasses.replace(start, controller=seed.controller), seed)
    # the morphology starts where the PD variant's does, gene for gene
    pd_task = load_task(TASKS / 'task1.yaml')
    pd_spec = genome_spec(pd_task)
    morphology = [name for name in spec.names if not name.startswith('controller.')]
    assert morphology == [name for name in pd_spec.names if not name.startswith('controller.')]
    pd_x = seed_genome(pd_task)
    assert x[[spec.index(name) for name in morphology]] == pytest.approx(
        pd_x[[pd_spec.index(name) for name in morphology]], abs=1e-15)
    assert make_optimizer(task, spec.size).x0 == pytest.approx(x, abs=0.0)


def test_seeded_start_centres_the_genes_the_seed_has_no_value_for():
    # Task 1's seed joints have no limits; searching limits starts them at the centre.
    text = (TASKS / 'task1.yaml').read_text().replace('joint_limits: none',
                                                      'joint_limits: {bounds: [-1, 1]}')
    task = parse_task(text, source='limits.yaml')
    spec = genome_spec(task)
    x = spec.seed_mean()
    limits = [index for index, name in enumerate(spec.names) if name.endswith('_limit')]
    assert len(limits) == 12 and (x[limits] == 0.5).all()
    assert np.isnan(spec.seed_values[limits]).all()
    seeded = np.delete(np.arange(spec.size), limits)
    assert not np.isnan(spec.seed_values[seeded]).any()
    start = spec.decode(x)
    assert start.controller == task.seed_design.controller
    assert [j.axis_angle for f in start.hand.fingers for j in f.joints] == pytest.approx(
        [j.axis_angle for f in task.seed_design.hand.fingers for j in f.joints])
    assert genome_spec(load_task(TASKS / 'task5.yaml')).seed_mean() is None


def test_decode_function_and_bad_shapes():
    task = load_task(TASKS / 'task6.yaml')
    spec = genome_spec(task)
    assert decode(spec.initial_mean(), task) == spec.decode(spec.initial_mean())
    with pytest.raises(ValueError, match=r'expected \(24,\)'):
        spec.decode(np.zeros(3))


def test_objective_names_and_weights():
    task = load_task(TASKS / 'task4.yaml')
    assert objective_names(task) == ['position_1', 'orientation_1']
    assert list(task.objective_weights) == [1.0, 0.1]
    task1 = load_task(TASKS / 'task1.yaml')
    assert objective_names(task1)[3:5] == ['position_4', 'orientation_1']
    assert list(task1.objective_weights) == [1.0] * 4 + [0.1] * 4
