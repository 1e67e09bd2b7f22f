"""
The launch file of `ros2 launch hand_codesign codesign.launch.py`, checked without launch.

ROS's launch packages are not on PyPI, so this machine cannot run it: the file parses,
declares the arguments the README names, and every executable, parameter and file it names
exists. test_colcon.py checks that a colcon build installs it under share/hand_codesign/launch.
"""

import ast
import importlib
import importlib.metadata
import pathlib

import yaml

ROOT = pathlib.Path(__file__).resolve().parents[1]
LAUNCH_FILE = ROOT / 'launch' / 'codesign.launch.py'


def launch_tree():
    return ast.parse(LAUNCH_FILE.read_text(), filename=str(LAUNCH_FILE))


def node_calls():
    """Return (executable, [parameter file names], {parameter: value node}) per Node(...)."""
    calls = []
    for call in ast.walk(launch_tree()):
        if not (isinstance(call, ast.Call) and getattr(call.func, 'id', '') == 'Node'):
            continue
        keywords = {keyword.arg: keyword.value for keyword in call.keywords}
        files, overrides = [], {}
        for item in keywords['parameters'].elts:
            if isinstance(item, ast.Call) and item.func.id == 'parameter_file':
                files.append(ast.literal_eval(item.args[0]))
            else:
                overrides.update({ast.literal_eval(key): value
                                  for key, value in zip(item.keys, item.values)})
        calls.append((ast.literal_eval(keywords['executable']), files, overrides))
    return calls


def parameter_table(executable):
    """Return the PARAMETERS table of the node an installed executable runs."""
    entry_points = {entry.name: entry.value for entry in
                    importlib.metadata.distribution('hand_codesign').entry_points}
    module = importlib.import_module(entry_points[executable].split(':')[0])
    # the optimizer executable wraps ros.optimizer_node with a bag reader for resuming
    return getattr(module, 'PARAMETERS', None) or importlib.import_module(
        f'hand_codesign.ros.{executable}_node').PARAMETERS


def test_the_launch_file_parses_and_declares_the_readmes_arguments():
    compile(LAUNCH_FILE.read_text(), str(LAUNCH_FILE), 'exec')
    tree = launch_tree()
    functions = {node.name for node in tree.body if isinstance(node, ast.FunctionDef)}
    assert 'generate_launch_description' in functions
    arguments = next(ast.literal_eval(node.value) for node in tree.body
                     if isinstance(node, ast.Assign) and node.targets[0].id == 'ARGUMENTS')
    assert {'task_file', 'evaluators', 'bag', 'seed'} <= set(arguments)
    assert (ROOT / arguments['task_file'][0]).is_file()   # the default task, in share/ too


def test_every_executable_parameter_and_file_it_names_exists():
    calls = node_calls()
    assert sorted(executable for executable, _, _ in calls) == [
        'evaluator', 'optimizer', 'recorder']
    for executable, files, overrides in calls:
        table = parameter_table(executable)
        assert set(overrides) <= set(table), (executable, set(overrides) - set(table))
        assert files == [f'{executable}.yaml']
        for name in files:   # installed from config/ into share/config (setup.py)
            document = yaml.safe_load((ROOT / 'config' / name).read_text())
            given = document['/**']['ros__parameters']
            assert set(given) <= set(table), (name, set(given) - set(table))
