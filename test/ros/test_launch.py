"""
The launch file of `ros2 launch hand_codesign codesign.launch.py`, checked without launch.

ROS's launch packages are not on PyPI, so this machine cannot run it. The test loads the file
with stand-ins for the launch classes that only record what they are given, and asks it for
its nodes as `ros2 launch` would with the arguments a user types: every executable,
parameter and file it names exists, the launch arguments reach the optimizer over the
parameter files, and a bad argument ends in one line. test_colcon.py checks that a colcon
build installs it under share/hand_codesign/launch.
"""

import importlib
import importlib.metadata
import importlib.util
import pathlib
import re
import sys
import types

import pytest
import yaml

ROOT = pathlib.Path(__file__).resolve().parents[2]
LAUNCH_FILE = ROOT / 'launch' / 'codesign.launch.py'
STAND_INS = {
    'launch': ['LaunchDescription'],
    'launch.actions': ['DeclareLaunchArgument', 'EmitEvent', 'OpaqueFunction',
                       'RegisterEventHandler', 'TimerAction'],
    'launch.event_handlers': ['OnProcessExit'],
    'launch.events': ['Shutdown'],
    'launch_ros': [],
    'launch_ros.actions': ['Node'],
}


class Recorded:
    """A launch class's stand-in: keeps its arguments."""

    def __init__(self, *arguments, **keywords):
        self.arguments, self.keywords = arguments, keywords


@pytest.fixture
def launch_file(monkeypatch):
    """Return the launch file as a module, its launch imports given stand-ins."""
    for name, classes in STAND_INS.items():
        module = types.ModuleType(name)
        for class_name in classes:
            setattr(module, class_name, type(class_name, (Recorded,), {}))
        monkeypatch.setitem(sys.modules, name, module)
    spec = importlib.util.spec_from_file_location('codesign_launch', LAUNCH_FILE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    # share/config of an installed package holds config/*.yaml (test_colcon checks it)
    monkeypatch.setattr(module, 'get_package_share_directory', lambda package: str(ROOT))
    return module


def nodes(launch_file, **typed):
    """Return {executable: [(parameter files, {parameter: value}) per node]} for arguments."""
    description = launch_file.generate_launch_description()
    declared = {action.arguments[0]: action.keywords['default_value']
                for action in description.arguments[0] if type(action).__name__ ==
                'DeclareLaunchArgument'}
    opaque = description.arguments[0][-1]
    unknown = set(typed) - set(declared)
    assert not unknown, f'not declared: {unknown}'
    context = types.SimpleNamespace(launch_configurations={**declared, **typed})
    found = {}
    for action in opaque.keywords['function'](context):
        if type(action).__name__ != 'Node':
            continue
        parameters = action.keywords['parameters']
        files = [item for item in parameters if isinstance(item, str)]
        values = {key: value for item in parameters if isinstance(item, dict)
                  for key, value in item.items()}
        found.setdefault(action.keywords['executable'], []).append((files, values))
    return found


def parameter_table(executable):
    """Return the PARAMETERS table of the node an installed executable runs."""
    entry_points = {entry.name: entry.value for entry in
                    importlib.metadata.distribution('hand_codesign').entry_points}
    module = importlib.import_module(entry_points[executable].split(':')[0])
    # the optimizer executable wraps ros.optimizer_node with a bag reader for resuming
    return getattr(module, 'PARAMETERS', None) or importlib.import_module(
        f'hand_codesign.ros.{executable}_node').PARAMETERS


def test_it_declares_the_arguments_the_readme_and_its_docstring_name(launch_file):
    declared = set(launch_file.ARGUMENTS)
    readme = (ROOT / 'README.md').read_text()
    command = readme[readme.index('ros2 launch hand_codesign'):].split('```')[0]
    assert set(re.findall(r'(\w+):=', command)) <= declared
    documented = set(re.findall(r'^    (\w+)  ', launch_file.__doc__, re.M))
    assert documented == declared
    assert (ROOT / launch_file.ARGUMENTS['task_file'][0]).is_file()


def test_every_executable_parameter_and_file_it_names_exists(launch_file, tmp_path):
    mine = tmp_path / 'mine.yaml'
    mine.write_text('{}\n')
    found = nodes(launch_file, live='true', params_file=str(mine), population='8')
    assert sorted(found) == ['evaluator', 'live_view', 'optimizer', 'recorder', 'robot_view']
    for executable, calls in found.items():
        table = parameter_table(executable)
        for files, values in calls:
            assert set(values) <= set(table), (executable, set(values) - set(table))
            assert files[-1:] == [str(mine)] or executable == 'live_view'
            for path in files[:-1]:   # the package's own, from config/ (setup.py)
                document = yaml.safe_load(pathlib.Path(path).read_text())
                given = document['/**']['ros__parameters']
                assert set(given) <= set(table), (path, set(given) - set(table))


def test_by_default_the_parameter_files_decide(launch_file):
    found = nodes(launch_file)
    assert sorted(found) == ['evaluator', 'optimizer', 'recorder', 'robot_view']
    assert len(found['evaluator']) == 2
    (files, values), = found['optimizer']
    assert [pathlib.Path(path).name for path in files] == ['optimizer.yaml']
    assert not {'seed', 'engine', 'iterations', 'population', 'world_states'} & set(values)


def test_the_budget_engine_and_params_file_reach_the_optimizer(launch_file, tmp_path):
    mine = tmp_path / 'mine.yaml'
    mine.write_text('/**:\n  ros__parameters:\n    audit_fraction: 0.0\n')
    found = nodes(launch_file, engine='mujoco', iterations='3', population='8',
                  world_states='4', seed='5', params_file=str(mine), evaluators='3')
    (files, values), = found['optimizer']
    assert files[-1] == str(mine)   # after the package's own file, so its values win
    assert {key: values[key] for key in ('engine', 'iterations', 'population', 'world_states',
                                         'seed')} == {
        'engine': 'mujoco', 'iterations': 3, 'population': 8, 'world_states': 4, 'seed': 5}
    assert len(found['evaluator']) == 3
    assert all(files[-1] == str(mine) for files, _ in found['evaluator'] + found['recorder'])


def test_live_starts_the_live_view_on_the_port_given(launch_file):
    (files, values), = nodes(launch_file, live='true', live_port='0')['live_view']
    assert values == {'port': 0}


@pytest.mark.parametrize('argument, value, words', [
    ('iterations', 'ten', 'launch argument iterations: expected a whole number >= 0, got "ten"'),
    ('population', '-2', 'launch argument population: expected a whole number >= 0, got "-2"'),
    ('engine', 'ode', 'launch argument engine: expected pybullet or mujoco, got "ode"'),
    ('live', 'yes', 'launch argument live: expected true or false, got "yes"'),
    ('params_file', '/no/such.yaml', 'launch argument params_file: no such file'),
])
def test_a_bad_argument_ends_in_one_line(launch_file, argument, value, words):
    with pytest.raises(ValueError) as raised:
        nodes(launch_file, **{argument: value})
    assert str(raised.value).startswith(words) and '\n' not in str(raised.value)
