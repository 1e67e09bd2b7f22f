"""Task files: every preset loads, and each kind of mistake names file, key and expectation."""

import math
import pathlib

from hand_codesign.core import genome_spec, load_task, parse_task, Task, TaskError
from hand_codesign.core.task import PhysicsSpec, WorldsSpec
import pytest
import yaml

ROOT = pathlib.Path(__file__).resolve().parents[3]
PRESETS = sorted((ROOT / 'config' / 'tasks').glob('*.yaml'))
TASK5 = ROOT / 'config' / 'tasks' / 'task5.yaml'


def task5_document():
    return yaml.safe_load(TASK5.read_text())


def write_task(tmp_path, document, name='bad.yaml'):
    path = tmp_path / name
    path.write_text(yaml.safe_dump(document, sort_keys=False))
    return path


def test_presets_cover_table_one():
    names = {path.stem for path in PRESETS}
    assert {'task1', 'task2', 'task3', 'task4', 'task5', 'task6'} <= names


@pytest.mark.parametrize('path', PRESETS, ids=lambda path: path.stem)
def test_every_preset_loads(path):
    task = load_task(path)
    assert isinstance(task, Task)
    assert task.name == path.stem
    assert task.source_text == path.read_text()
    assert task.time_step == 0.005
    assert task.initial_sigma == 0.1
    assert task.weights.position == 1.0 and task.weights.orientation == 0.1
    assert len(task.objective_weights) == len(task.objective_names) > 0
    spec = genome_spec(task)
    assert spec.size > 0 and (spec.lower < spec.upper).all()


def test_table_one_values():
    task4 = load_task(ROOT / 'config' / 'tasks' / 'task4.yaml')
    assert task4.structure == (1,) and task4.hierarchy.start == (1,)
    assert task4.hierarchy.stop_structure == (2, 3)
    assert (task4.algorithm, task4.iterations, task4.population) == ('mocma', 200, 150)
    assert task4.morphology.segment_length.per_finger_total
    task5 = load_task(TASK5)
    assert task5.structure == (2, 2) and task5.policy.knots == 2
    assert task5.policy.torque.values[0].upper == 0.01
    task2 = load_task(ROOT / 'config' / 'tasks' / 'task2.yaml')
    assert task2.early_termination.distance == 0.5 and task2.early_termination.angle == 0.5
    assert task2.object_spec.shape == 'sphere' and task2.object_spec.radius == 0.35
    for name in ('task1', 'task2'):
        seeded = load_task(ROOT / 'config' / 'tasks' / f'{name}.yaml')
        assert seeded.seed_design is not None
        assert seeded.seed_design.hand.structure == seeded.structure
        assert seeded.seed_design.controller.kind == 'pd'
        assert 'stand-in' in seeded.source_text


def test_goal_axes_and_symmetry():
    task5 = load_task(TASK5)
    assert task5.goals.position[0].axes == ('x', 'y')  # the paper's task: the plane (issue 26)
    variant = load_task(ROOT / 'config' / 'tasks' / 'task5_along_x.yaml')
    assert variant.goals.position[0].axes == ('x',)  # the named variant: the fingers' axis
    assert variant.replace(goals=task5.goals, name=task5.name, source_text=task5.source_text,
                           source=task5.source, description=task5.description) == task5
    pinned = load_task(ROOT / 'config' / 'reproduce' / 'task5.yaml')
    assert pinned.goals.position[0].axes == ('x', 'y')  # as the paper's experiments ran
    assert task5.goals.orientation_symmetry.axis == (0.0, 0.0, 1.0)
    assert task5.goals.orientation_symmetry.order == 4
    assert task5.objective_names == ('position_1', 'orientation_1')
    assert list(task5.objective_weights) == [1.0, 0.1]
    task1 = load_task(ROOT / 'config' / 'tasks' / 'task1.yaml')
    assert {goal.axes for goal in task1.goals.position} == {('x', 'y', 'z')}  # the default
    assert task1.goals.orientation_symmetry is None


def test_physics_defaults_are_table_one_and_a_section_overrides_them(tmp_path):
    assert load_task(TASK5).physics == PhysicsSpec(50, 0.02)
    document = task5_document()
    document['physics'] = {'solver_iterations': 5}
    task = load_task(write_task(tmp_path, document, 'fast.yaml'))
    assert task.physics == PhysicsSpec(solver_iterations=5, contact_breaking_threshold=0.02)
    document['physics'] = {'engine': 'mujoco'}
    task = load_task(write_task(tmp_path, document, 'mujoco.yaml'))
    assert task.physics == PhysicsSpec(engine='mujoco')


def test_worlds_default_to_the_mean_on_fixed_worlds_and_a_section_sets_them(tmp_path):
    for path in sorted(TASK5.parent.glob('*.yaml')):  # every preset keeps eq. (5)
        assert load_task(path).worlds == WorldsSpec('mean', 1.0, 'none', 5), path.name
    document = task5_document()
    document['worlds'] = {'aggregate': 'worst', 'fraction': 0.25, 'resample': 'generation',
                          'final_check': 3}
    task = load_task(write_task(tmp_path, document, 'robust.yaml'))
    assert task.worlds == WorldsSpec('worst', 0.25, 'generation', 3)
    assert task.worlds.worst_fraction == 0.25 and WorldsSpec().worst_fraction == 1.0


def test_resampled_worlds_do_not_combine_with_a_hierarchy_two_stages_or_a_horizon(tmp_path):
    for name, expected in (('task4.yaml', 'a hierarchy'), ('task5.yaml', 'two stages'),
                           ('task3.yaml', 'a horizon')):
        document = yaml.safe_load((TASK5.parent / name).read_text())
        document['worlds'] = {'resample': 'generation'}
        document['two_stage'] = name == 'task5.yaml'
        path = write_task(tmp_path, document, name)
        with pytest.raises(TaskError, match=rf'{name}: worlds.resample: expected none in a '
                           rf'task with {expected} \(not supported'):
            load_task(path)
    task = load_task(TASK5)
    with pytest.raises(TaskError, match='world_draw: expected 0 for the held-out worlds'):
        task.replace(world_draw=2, held_out=True)
    with pytest.raises(TaskError, match='world_draw: expected an integer >= 0'):
        task.replace(world_draw=-1)


def test_angles_take_pi_expressions():
    task = load_task(TASK5)
    bounds = task.morphology.initial_angle.values[0]
    assert bounds.lower == pytest.approx(-math.pi / 2)
    assert bounds.upper == pytest.approx(math.pi / 2)
    assert task.morphology.axis_angle.values[0] == pytest.approx(math.pi / 2)


def test_replace_changes_and_validates():
    task = load_task(TASK5)
    changed = task.replace(seed=3, iterations=5, population=8, num_world_states=4,
                           structure=[1, 2])
    assert (changed.seed, changed.iterations, changed.population) == (3, 5, 8)
    assert changed.structure == (1, 2) and changed.source_text == task.source_text
    assert changed != task and task == load_task(TASK5)
    assert hash(task) == hash(load_task(TASK5))
    with pytest.raises(TaskError, match=r'task5.yaml: optimizer.population: expected a'):
        task.replace(population=-3)
    with pytest.raises(TaskError, match='morphology.finger_position_x: expected one entry per '
                                        'finger'):
        task.replace(structure=(2, 2, 2))


def test_seeded_tasks_hash():
    task = load_task(ROOT / 'config' / 'tasks' / 'task1.yaml')
    assert task == load_task(ROOT / 'config' / 'tasks' / 'task1.yaml')
    assert len({task, task.replace(seed=0)}) == 1


def test_parse_task_names_its_source():
    text = TASK5.read_text().replace('population: 80', 'population: -3')
    with pytest.raises(TaskError) as error:
        parse_task(text, source='bag:run_info')
    assert str(error.value).startswith('bag:run_info: optimizer.population: expected a '
                                       'positive integer, got -3')


def test_seed_design_from_a_file(tmp_path):
    document = yaml.safe_load((ROOT / 'config' / 'tasks' / 'task1.yaml').read_text())
    (tmp_path / 'seeds').mkdir()
    (tmp_path / 'seeds' / 'hand.yaml').write_text(yaml.safe_dump(document['seed_design']))
    document['seed_design'] = 'seeds/hand.yaml'
    task = load_task(write_task(tmp_path, document, 'seeded.yaml'))
    assert task.seed_design == load_task(ROOT / 'config' / 'tasks' / 'task1.yaml').seed_design
    document['seed_design'] = 'seeds/missing.yaml'
    with pytest.raises(TaskError, match=r'seeded.yaml: seed_design: expected a readable seed'):
        load_task(write_task(tmp_path, document, 'seeded.yaml'))


def set_key(document, dotted, value):
    *parents, last = dotted.split('.')
    for name in parents:
        document = document[name]
    document[last] = value


def delete_key(document, dotted):
    *parents, last = dotted.split('.')
    for name in parents:
        document = document[name]
    del document[last]


BAD_VALUES = [
    # (dotted key, new value, expected text in the message)
    ('optimizer.population', -3, 'expected a positive integer, got -3'),
    ('optimizer.iterations', 'many', "expected a positive integer, got 'many'"),
    ('object.mass', -0.03, 'expected a positive number, got -0.03'),
    ('object.shape', 'cylinder', "expected one of sphere, box, capsule, got 'cylinder'"),
    ('object.friction', 'high', "expected a number, got 'high'"),
    ('morphology.segment_length', {'bounds': [0.09, 0.04]},
     'expected lower <= upper, got [0.09, 0.04]'),
    ('randomization.scale', [1.5, 0.66], 'expected lower <= upper'),
    ('goals.distance', 'chebyshev', 'expected one of euclidean, manhattan'),
    ('optimizer.algorithm', 'nsga3', 'expected one of cma, mocma, ipop-cma, bipop-cma, cma-mae, '
     'cma-me'),
    ('optimizer.restart_stagnation', 0, 'expected a positive integer, got 0'),
    ('optimizer.restart_stagnation', 5, 'expected no restart_stagnation for cma (it is for '
     'ipop-cma and bipop-cma, which restart CMA-ES)'),
    ('policy.mode', 'random', 'expected one of constant, interpolated'),
    ('hand.structure', [2, 0], 'expected a positive integer, got 0'),
    ('object.position', [0.0, 0.0, 0.5], 'for an object resting on the plane'),
    ('time_step', 0.0, 'expected a positive number'),
    ('goals.position', [{'time': 9.0, 'position': [0, 0, 0.02], 'trajectory': False}],
     'expected a time within the duration'),
    ('morphology.friction', {'delta': [-0.1, 0.1]}, 'expected a seed_design'),
    ('goals.position', [{'time': 1.5, 'position': [0, 0, 0.02], 'axes': ['x', 'w'],
                         'trajectory': False}],
     'goals.position[0].axes: expected a non-empty list of distinct world axes from x, y, z, '
     "e.g. [x, y], got ['x', 'w']"),
    ('goals.position', [{'time': 1.5, 'position': [0, 0, 0.02], 'axes': ['x', 'x'],
                         'trajectory': False}], 'axes: expected a non-empty list of distinct'),
    ('goals.position', [{'time': 1.5, 'position': [0, 0, 0.02], 'axes': [],
                         'trajectory': False}], 'axes: expected a non-empty list of distinct'),
    ('goals.orientation_symmetry', {'axis': [0, 0, 1], 'order': 1},
     'goals.orientation_symmetry.order: expected an integer >= 2, got 1'),
    ('goals.orientation_symmetry', {'axis': [0, 0, 0], 'order': 4},
     'goals.orientation_symmetry.axis: expected a non-zero vector'),
    ('goals.orientation_symmetry', {'axis': [0, 0, 1]},
     'goals.orientation_symmetry.order: expected this key'),
    ('physics', {'solver_iterations': 0}, 'physics.solver_iterations: expected a positive '
     'integer, got 0'),
    ('physics', {'contact_breaking_threshold': -0.01}, 'physics.contact_breaking_threshold: '
     'expected a positive number, got -0.01'),
    ('physics', {'substeps': 2}, 'physics.substeps: expected no such key'),
    ('physics', {'engine': 'ode'}, 'physics.engine: expected one of pybullet, mujoco, '
     "got 'ode'"),
    ('worlds', {'aggregate': 'worst'}, 'worlds.fraction: expected this key with aggregate: '
     'worst'),
    ('worlds', {'aggregate': 'worst', 'fraction': 0}, 'worlds.fraction: expected a fraction '
     'in (0, 1], got 0'),
    ('worlds', {'aggregate': 'worst', 'fraction': 1.5}, 'worlds.fraction: expected a fraction '
     'in (0, 1], got 1.5'),
    ('worlds', {'aggregate': 'worst', 'fraction': 'a quarter'}, 'worlds.fraction: expected a '
     "number, got 'a quarter'"),
    ('worlds', {'fraction': 0.5}, 'worlds.fraction: expected no fraction with aggregate: mean'),
    ('worlds', {'aggregate': 'median'}, 'worlds.aggregate: expected one of mean, worst'),
    ('worlds', {'resample': 'always'}, 'worlds.resample: expected one of none, generation'),
    ('worlds', {'final_check': 3}, 'worlds.final_check: expected no final_check with '
     'resample: none (only with resample: generation)'),
    ('worlds', {'resample': 'generation', 'final_check': 0}, 'worlds.final_check: expected a '
     'positive integer, got 0'),
    ('worlds', {'resample': 'generation', 'repeats': 2}, 'worlds.repeats: expected no such key'),
]


@pytest.mark.parametrize('key,value,expected', BAD_VALUES, ids=[case[0] for case in BAD_VALUES])
def test_bad_values_name_file_key_and_expectation(tmp_path, key, value, expected):
    document = task5_document()
    set_key(document, key, value)
    path = write_task(tmp_path, document)
    with pytest.raises(TaskError) as error:
        load_task(path)
    message = str(error.value)
    assert message.startswith(f'{path}: ')
    assert key.split('.')[0] in message and expected in message, message


def test_wrong_type_names_the_nested_key(tmp_path):
    document = task5_document()
    document['randomization']['position']['x'] = 0.005
    path = write_task(tmp_path, document)
    with pytest.raises(TaskError, match=r'bad.yaml: randomization.position.x: expected a pair '
                                        r'\[lower, upper\], got 0.005'):
        load_task(path)


@pytest.mark.parametrize('key', ['object.mass', 'optimizer.population', 'goals.distance',
                                 'morphology.joint_limits', 'seed'])
def test_missing_key(tmp_path, key):
    document = task5_document()
    delete_key(document, key)
    path = write_task(tmp_path, document)
    with pytest.raises(TaskError) as error:
        load_task(path)
    assert str(error.value) == f'{path}: {key}: expected this key (it is missing)'


@pytest.mark.parametrize('key', ['colour', 'object.colour', 'policy.gains'])
def test_unknown_key(tmp_path, key):
    document = task5_document()
    set_key(document, key, 1)
    path = write_task(tmp_path, document)
    with pytest.raises(TaskError) as error:
        load_task(path)
    message = str(error.value)
    assert message.startswith(f'{path}: {key}: expected no such key (allowed: ')


def test_shape_needs_its_own_sizes(tmp_path):
    document = task5_document()
    document['object']['shape'] = 'sphere'
    with pytest.raises(TaskError, match=r'object.size: expected no size for a sphere'):
        load_task(write_task(tmp_path, document))
    del document['object']['size']
    with pytest.raises(TaskError, match=r'object.radius: expected this key for a sphere'):
        load_task(write_task(tmp_path, document))


def test_unreadable_and_invalid_files(tmp_path):
    with pytest.raises(TaskError, match=r'missing.yaml: cannot read the task file'):
        load_task(tmp_path / 'missing.yaml')
    path = tmp_path / 'broken.yaml'
    path.write_text('name: [unclosed\n')
    with pytest.raises(TaskError, match=r'broken.yaml: not valid YAML'):
        load_task(path)
    path.write_text('- a list\n')
    with pytest.raises(TaskError, match=r'broken.yaml: top level: expected a mapping'):
        load_task(path)
