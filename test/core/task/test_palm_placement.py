"""The palm's placement searched (beyond the paper): hand.base_position bounds, hand.base_yaw."""

import pathlib

from analysis_run import run_codesign
from hand_codesign.analysis.export import design_document
from hand_codesign.analysis.records import evaluation_rows, open_run
from hand_codesign.cli import main
from hand_codesign.core import genome_spec, load_task, Simulator
from hand_codesign.core.evaluate import evaluate_design
from hand_codesign.core.rotations import axis_angle_quaternion, quaternion_multiply
from hand_codesign.core.sim.hand import hand_model
from hand_codesign.core.sim.mujoco_sim import MujocoSimulator
from hand_codesign.core.sim.physical import design_from_physical, physical_design
from hand_codesign.core.task import parse_design, parse_task, TaskError
import numpy as np
import pytest
import yaml

TASK5 = pathlib.Path(__file__).resolve().parents[3] / 'config' / 'tasks' / 'task5.yaml'
PALM = ('hand.base_position_x', 'hand.base_position_y', 'hand.base_yaw')


def palm_document(position=None, yaw=None):
    """Return task5.yaml as a dict with hand.base_position and hand.base_yaw replaced."""
    document = yaml.safe_load(TASK5.read_text())
    if position is not None:
        document['hand']['base_position'] = position
    if yaw is not None:
        document['hand']['base_yaw'] = yaw
    return document


def palm_task(**keys):
    """Return Task 5 with x, y within 1 cm and the yaw within 0.2 rad searched."""
    keys.setdefault('position', {'bounds': [[-0.01, 0.01], [-0.01, 0.01], [0.15, 0.15]]})
    keys.setdefault('yaw', {'bounds': [-0.2, 0.2]})
    return parse_task(yaml.safe_dump(palm_document(**keys)), source='palm.yaml')


def test_the_reader_takes_bounds_and_the_genome_searches_them():
    task = palm_task()
    assert task.hand.base_position == pytest.approx((0.0, 0.0, 0.15))   # the centre
    assert [(b.lower, b.upper) for b in task.hand.base_position_bounds] == [
        (-0.01, 0.01), (-0.01, 0.01), (0.15, 0.15)]
    assert task.hand.placement_searched
    spec = genome_spec(task)
    preset = genome_spec(load_task(TASK5))
    assert spec.names[:4] == ['hand.base_position_x', 'hand.base_position_y', 'hand.base_yaw',
                              preset.names[0]]                 # z stays fixed: no gene
    assert spec.names[3:] == preset.names
    assert spec.lower[2] == pytest.approx(-0.2) and spec.upper[2] == pytest.approx(0.2)
    centre = spec.decode(spec.initial_mean()).hand
    assert centre.base_position == pytest.approx((0.0, 0.0, 0.15)) and centre.base_yaw == 0.0


@pytest.mark.parametrize('position, yaw', [
    ([0.0, 0.0, 0.15], None), ({'fixed': [0.0, 0.0, 0.15]}, 0.0), (None, {'fixed': 0}),
    ({'bounds': [[0.0, 0.0], [0.0, 0.0], [0.15, 0.15]]}, {'bounds': [0, 0]})])
def test_a_fixed_placement_keeps_the_genome_and_the_results_of_the_preset(position, yaw):
    preset = load_task(TASK5).replace(num_world_states=2)
    fixed = palm_task(position=position, yaw=yaw).replace(num_world_states=2)
    assert not fixed.hand.placement_searched
    spec, before = genome_spec(fixed), genome_spec(preset)
    assert spec.names == before.names and spec.size == before.size
    x = np.random.default_rng(5).normal(0.5, 0.2, spec.size)
    design = spec.decode(x)
    assert design == before.decode(x) and design.hand.base_position is None
    assert hand_model(design.hand, fixed.hand) == hand_model(design.hand, preset.hand)
    ours, theirs = evaluate_design(design, fixed), evaluate_design(design, preset)
    assert np.array_equal(ours.objectives, theirs.objectives)


@pytest.mark.parametrize('position, yaw, message', [
    ({'bounds': [[-0.01, 0.01], [0.0, 0.0]]}, None,
     'hand.base_position.bounds: expected three pairs [[x lower, x upper], [y lower, y upper], '
     '[z lower, z upper]], got [[-0.01, 0.01], [0.0, 0.0]]'),
    ({'bounds': [[0.01, -0.01], [0, 0], [0.15, 0.15]]}, None,
     'hand.base_position.bounds[0]: expected lower <= upper, got [0.01, -0.01]'),
    ({'range': [[0, 0], [0, 0], [0, 0]]}, None,
     'hand.base_position: expected [x, y, z] or {fixed: [x, y, z]} or {bounds: [[x lower, '
     'x upper], [y lower, y upper], [z lower, z upper]]}, got {"range": [[0, 0], [0, 0], '
     '[0, 0]]}'.replace('"', "'")),
    ([0.0, 0.15], None, 'hand.base_position: expected a list of 3 numbers, got [0.0, 0.15]'),
    (None, {'bounds': [0.3]}, 'hand.base_yaw.bounds: expected a pair [lower, upper], got [0.3]'),
    (None, [-0.2, 0.2], 'hand.base_yaw: expected a number or {fixed: v} or {bounds: [lower, '
     'upper]}, got [-0.2, 0.2]'),
    (None, {'bounds': [0.2, -0.2]}, 'hand.base_yaw.bounds: expected lower <= upper'),
])
def test_bad_placements_are_one_line_naming_the_key(position, yaw, message):
    document = palm_document(position=position, yaw=yaw)
    with pytest.raises(TaskError) as error:
        parse_task(yaml.safe_dump(document), source='palm.yaml')
    text = str(error.value)
    assert '\n' not in text and text.startswith('palm.yaml: ') and message in text


def palm_poses(engine, task, design):
    """Return the palm body's (position, orientation x, y, z, w) as the engine built it."""
    model = hand_model(design.hand, task.hand)
    with engine() as simulator:
        simulator.build(task, model)
        if simulator.engine == 'mujoco':
            import mujoco
            data = simulator.mj_data
            mujoco.mj_kinematics(simulator.mj_model, data)
            body = simulator.mj_model.body('palm').id
            w, x, y, z = data.xquat[body]
            return np.array(data.xpos[body]), np.array((x, y, z, w))
        position, orientation = simulator.client.getBasePositionAndOrientation(simulator.hand)
        return np.array(position), np.array(orientation)


def same_turn(first, second):
    return abs(float(np.dot(first, second))) == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize('engine', [Simulator, MujocoSimulator])
def test_two_genomes_place_the_palm_at_two_poses_in_each_engine(engine):
    task = palm_task()
    spec = genome_spec(task)
    poses = []
    for value in (0.1, 0.8):
        x = spec.initial_mean()
        x[[spec.index(name) for name in PALM]] = value
        design = spec.decode(x)
        position, orientation = palm_poses(engine, task, design)
        wanted_yaw = -0.2 + value * 0.4
        np.testing.assert_allclose(position, (-0.01 + value * 0.02,) * 2 + (0.15,), atol=1e-9)
        wanted = quaternion_multiply(axis_angle_quaternion((0, 0, 1), wanted_yaw),
                                     task.hand.base_orientation)
        assert design.hand.base_yaw == pytest.approx(wanted_yaw)
        assert same_turn(orientation, wanted)
        poses.append((position, orientation))
    assert np.linalg.norm(poses[0][0] - poses[1][0]) > 0.01
    assert not same_turn(poses[0][1], poses[1][1])


def test_a_placed_design_survives_its_document_and_its_physical_fields():
    task = palm_task()
    spec = genome_spec(task)
    x = spec.initial_mean()
    x[[spec.index(name) for name in PALM]] = (0.2, 0.7, 0.9)
    design = spec.decode(x)
    assert parse_design(design_document(design), 'design.yaml', key='') == design
    physical = physical_design(design, task)
    assert physical.names[-4:] == ('hand.base_position_x', 'hand.base_position_y',
                                   'hand.base_position_z', 'hand.base_yaw')
    back = design_from_physical(task.structure, physical.names, physical.values, 'torque',
                                physical.controller_values)
    assert back == design
    assert np.allclose(spec.encode(design), x)


def test_a_start_inside_the_object_costs_the_collision_penalty():
    # the palm lowered onto the box: every world starts in collision
    task = palm_task(position={'bounds': [[0.0, 0.0], [0.0, 0.0], [0.0, 0.15]]})
    spec = genome_spec(task)
    x = spec.initial_mean()
    low, high = np.array(x), np.array(x)
    low[spec.index('hand.base_position_z')] = 0.0
    high[spec.index('hand.base_position_z')] = 1.0
    assert evaluate_design(spec.decode(low), task).collision
    assert not evaluate_design(spec.decode(high), task).collision


@pytest.mark.system
def test_a_short_search_records_palm_poses_and_replays_the_best(tmp_path, capsys):
    path = tmp_path / 'task5_palm.yaml'
    path.write_text(yaml.safe_dump(palm_document(
        position={'bounds': [[-0.01, 0.01], [-0.01, 0.01], [0.15, 0.15]]},
        yaw={'bounds': [-0.2, 0.2]})))
    bag = tmp_path / 'palm_run'
    run_codesign(bag, budget=['--iterations', '2', '--population', '6', '--world-states', '2',
                              '--seed', '3'], extra=['--evaluators', '1'], task=path)
    rows = evaluation_rows(open_run(bag))
    columns = [rows.gene_names.index(name) for name in PALM]
    palms = rows.genes[:, columns]
    assert len(np.unique(np.round(palms, 12), axis=0)) == len(palms) >= 12
    capsys.readouterr()
    assert main(['replay', str(bag)]) == 0
    assert 'replay reproduces the recorded objectives bit for bit' in capsys.readouterr().out
    assert not np.isnan(palms).any()


def test_check_lists_the_palm_genes_with_their_units(tmp_path, capsys):
    path = tmp_path / 'task5_palm.yaml'
    path.write_text(yaml.safe_dump(palm_document(
        position={'bounds': [[-0.01, 0.01], [-0.01, 0.01], [0.15, 0.15]]},
        yaw={'bounds': [-0.2, 0.2]})))
    assert main(['check', str(path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    rows = {line.split()[0]: line.split()[1:] for line in lines
            if line.strip().startswith('hand.base_')}
    assert rows == {'hand.base_position_x': ['-0.01', '0.01', 'm'],
                    'hand.base_position_y': ['-0.01', '0.01', 'm'],
                    'hand.base_yaw': ['-0.2', '0.2', 'rad']}
    assert 'genome: 27 values' in '\n'.join(lines)


def test_a_fixed_yaw_turns_the_palm_without_a_gene():
    task = palm_task(position=[0.0, 0.0, 0.15], yaw='pi/12')
    spec = genome_spec(task)
    assert spec.names == genome_spec(load_task(TASK5)).names
    design = spec.decode(spec.initial_mean())
    assert design.hand.base_yaw is None
    _, orientation = palm_poses(Simulator, task, design)
    assert same_turn(orientation, quaternion_multiply(
        axis_angle_quaternion((0, 0, 1), np.pi / 12), task.hand.base_orientation))
