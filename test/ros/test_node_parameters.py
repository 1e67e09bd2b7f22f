"""Nodes read their parameters once, check them against their ranges and say what is wrong."""

import os
import pathlib
import subprocess
import sys

import pytest

pytestmark = pytest.mark.system

ROOT = pathlib.Path(__file__).resolve().parents[2]
TASK = ROOT / 'config' / 'tasks' / 'task5.yaml'


def start_node(module, *parameters):
    command = [sys.executable, '-m', module, '--ros-args']
    for parameter in parameters:
        command += ['-p', parameter]
    env = dict(os.environ, ROS_DOMAIN_ID='149', RCUTILS_CONSOLE_OUTPUT_FORMAT='{message}')
    return subprocess.run(command, cwd=ROOT, env=env, capture_output=True, text=True,
                          timeout=120)


@pytest.mark.parametrize('module, parameters, message', [
    ('hand_codesign.commands.optimizer', ['population:=-3', f'task_file:={TASK}'],
     'Parameter population out of range. Min: 0, Max: 100000, value: -3'),
    ('hand_codesign.commands.optimizer', ['heartbeat_timeout:=0.0', f'task_file:={TASK}'],
     'Parameter heartbeat_timeout out of range'),
    ('hand_codesign.commands.optimizer', ['task_file:=no/such/task.yaml'],
     f'parameter task_file no/such/task.yaml: no such file in the working folder {ROOT} nor in '
     f'the package share/ {ROOT}'),
    ('hand_codesign.ros.optimizer_node', ['resume_bag:=some-bag'],
     'parameter resume_bag: this entry point cannot read bags; start `python -m '
     'hand_codesign.commands.optimizer`'),
    ('hand_codesign.ros.evaluator_node', ['capacity:=0'], 'Parameter capacity out of range'),
    ('hand_codesign.ros.recorder_node', ['topics:=[candidates, nope]'],
     "parameter topics: ['nope'] are not topics of the co-design loop"),
    ('hand_codesign.ros.live_node', ['port:=70000'], 'Parameter port out of range'),
])
def test_a_bad_parameter_stops_the_node_with_one_line(module, parameters, message):
    process = start_node(module, *parameters)
    assert process.returncode == 2, process.stderr
    lines = process.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], process.stderr
    assert 'Traceback' not in process.stderr + process.stdout
