"""
Bad input as a user gives it: one line, exit code 2, nothing written.

The line names the file and what was expected; no traceback; no bag, report, rollout or
output folder is left behind.
"""

import os
import pathlib
import shutil
import subprocess
import sys

from hand_codesign import cli
from hand_codesign.core.run.signing import RunKeys
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
TASK = ROOT / 'config' / 'tasks' / 'task5.yaml'
OTHER_TASK = ROOT / 'config' / 'tasks' / 'task6.yaml'


def one_line_error(capsys, verb, *arguments):
    """Run the CLI in this process; assert one error line and code 2; return the line."""
    code = cli.main([verb, *map(str, arguments)])
    output = capsys.readouterr()
    assert code == 2, output.out + output.err
    lines = output.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f'hand-codesign {verb}: error: '), lines
    return lines[0]


def nothing_but(folder, *names):
    return sorted(path.name for path in folder.iterdir()) == sorted(names)


@pytest.mark.parametrize('text, expected', [
    ('', 'empty.yaml: top level: expected a mapping'),
    ('# nothing but a comment\n', 'empty.yaml: top level: expected a mapping'),
])
def test_an_empty_task_file(capsys, tmp_path, text, expected):
    task = tmp_path / 'empty.yaml'
    task.write_text(text)
    assert expected in one_line_error(capsys, 'check', task)
    assert expected in one_line_error(capsys, 'run', '--task', task, '--bag', tmp_path / 'bag')
    assert nothing_but(tmp_path, 'empty.yaml')


def test_a_task_file_with_an_unknown_key(capsys, tmp_path):
    task = tmp_path / 'unknown.yaml'
    task.write_text(TASK.read_text() + '\npopulation_size: 12\n')
    line = one_line_error(capsys, 'run', '--task', task, '--bag', tmp_path / 'bag')
    assert 'unknown.yaml: population_size: expected no such key (allowed: name, ' in line
    line = one_line_error(capsys, 'check', task)
    assert 'population_size: expected no such key' in line
    assert nothing_but(tmp_path, 'unknown.yaml')


@pytest.mark.system
def test_resume_with_another_task_file(capsys, tmp_path, real_run):
    line = one_line_error(capsys, 'run', '--resume', real_run.bag, '--task', OTHER_TASK,
                          '--bag', tmp_path / 'resumed')
    assert '--resume takes the task, seed and budget from the bag; drop --task' in line
    assert nothing_but(tmp_path)


@pytest.mark.system
@pytest.mark.parametrize('size, expected', [
    (0, 'empty file; expected an MCAP bag'),
    (5, 'not an MCAP file'),
    (1000, 'an MCAP file without hand_codesign topics (the file is truncated)'),
])
def test_a_bag_whose_mcap_is_truncated(capsys, tmp_path, real_run, size, expected):
    bag = tmp_path / 'bag'
    shutil.copytree(real_run.bag, bag)
    with open(bag / real_run.mcap.name, 'r+b') as stream:
        stream.truncate(size)
    for verb, *arguments in (
            ('analyze', bag, '--out', tmp_path / 'report'),
            ('replay', bag, '--mcap', tmp_path / 'rollout.mcap'),
            ('export', bag, '--out', tmp_path / 'export'),
            ('robustness', bag, '--samples', 2, '--out', tmp_path / 'robustness'),
            ('run', '--resume', bag, '--bag', tmp_path / 'resumed')):
        line = one_line_error(capsys, verb, *arguments)
        assert str(bag) in line and expected in line
    assert nothing_but(tmp_path, 'bag')


def evaluator_with_key_file(key):
    """Start an evaluator node with a key file, on a domain of its own; return its end."""
    environment = dict(os.environ, ROS_DOMAIN_ID='0', ROS_AUTOMATIC_DISCOVERY_RANGE='OFF')
    return subprocess.run(
        [sys.executable, '-m', 'hand_codesign.ros.evaluator_node', '--ros-args',
         '-p', f'key_file:={key}'], env=environment, capture_output=True, text=True,
        timeout=60)


@pytest.mark.system
def test_key_files_with_wrong_permissions_or_length(tmp_path):
    credential = RunKeys(bytes(range(32))).credential('host-b')
    readable = tmp_path / 'readable.key'
    readable.write_text(credential.text())
    readable.chmod(0o644)
    short = tmp_path / 'short.key'
    short.write_text(credential.text().replace(credential.key.hex(), 'abcd'))
    short.chmod(0o600)
    for key, expected in (
            (readable, f'{readable} has mode 0644, so other users may read the key; expected '
                       '0600'),
            (short, f'key_file {short}: key and run_info_key must be 64 hex digits each')):
        ended = evaluator_with_key_file(key)
        assert ended.returncode == 2, ended.stdout + ended.stderr
        lines = (ended.stdout + ended.stderr).strip().splitlines()
        assert len(lines) == 1 and expected in lines[0], lines
    assert nothing_but(tmp_path, 'readable.key', 'short.key')
