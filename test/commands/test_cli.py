"""The `hand-codesign` command: its verbs, and bad flags answered with one clear line."""

import importlib.metadata
import os
import pathlib
import subprocess
import sys

from hand_codesign import cli
from hand_codesign.commands.run import run_domain
from hand_codesign.errors import UserError
from hand_codesign.ros.runner import ProgressThrottle
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
TASK = str(ROOT / 'config' / 'tasks' / 'task5.yaml')


def run(capsys, *argv):
    """Return (exit code, stdout, stderr) of the CLI called in this process."""
    # a run of a test takes a free ROS domain, never the shell's
    argv = [*argv, '--domain-id', 'auto'] if argv[:1] == ('run',) else argv
    code = cli.main([str(argument) for argument in argv])
    output = capsys.readouterr()
    return code, output.out, output.err


@pytest.mark.system
def test_help_lists_every_verb():
    output = subprocess.run([sys.executable, '-m', 'hand_codesign.cli', '--help'],
                            capture_output=True, text=True, check=True).stdout
    for verb in cli.VERBS:
        assert verb in output


def test_every_verb_loads_its_command():
    for verb in cli.VERBS:
        assert callable(cli.load_verb(verb))


@pytest.mark.parametrize('flags, message', [
    ([], '--task FILE is required'),
    (['--task', TASK, '--evaluators', '-1'], '--evaluators: expected 0 or more, got -1'),
    (['--task', TASK, '--population', '0'], '--population: expected a positive number, got 0'),
    (['--task', TASK, '--world-states', '-2'], '--world-states: expected a positive number'),
    (['--task', 'no/such/task.yaml'], 'no/such/task.yaml'),
    (['--resume', 'some-bag', '--seed', '3', '--population', '4'],
     '--resume takes the task, seed and budget from the bag; drop --seed, --population'),
])
def test_bad_run_flags_are_one_line_errors(capsys, flags, message):
    code, out, err = run(capsys, 'run', *flags)
    assert code == 2 and out == ''
    assert err.startswith('hand-codesign run: error: ') and message in err
    assert len(err.strip().splitlines()) == 1 and 'Traceback' not in err


def test_run_refuses_a_bag_that_exists_or_is_a_file(capsys, tmp_path):
    code, _, err = run(capsys, 'run', '--task', TASK, '--bag', tmp_path)
    assert code == 2 and 'already exists; choose a new path' in err
    code, _, err = run(capsys, 'run', '--task', TASK, '--bag', tmp_path / 'run.mcap')
    assert code == 2 and 'give a folder' in err


@pytest.mark.parametrize('verb', ['analyze', 'replay', 'export', 'robustness'])
def test_bag_verbs_name_a_missing_bag(capsys, tmp_path, verb):
    extra = ['--out', tmp_path / 'out'] if verb == 'export' else []
    code, _, err = run(capsys, verb, tmp_path / 'missing-bag', *extra)
    assert code == 2 and err.startswith(f'hand-codesign {verb}: error: ')
    assert 'missing-bag' in err and 'Traceback' not in err


@pytest.mark.system
def test_a_missing_verb_is_an_argparse_error():
    process = subprocess.run([sys.executable, '-m', 'hand_codesign.cli'], capture_output=True,
                             text=True)
    assert process.returncode == 2 and 'VERB' in process.stderr


def test_key_files_go_outside_the_bag_and_never_over_another_file(capsys, tmp_path):
    bag = tmp_path / 'bag'
    code, _, err = run(capsys, 'run', '--task', TASK, '--bag', bag, '--write-key-file',
                       f'host-b={bag / "host-b.key"}')
    assert code == 2 and 'is inside the bag folder, which must hold nothing secret' in err
    (tmp_path / 'old.key').write_text('x')
    code, _, err = run(capsys, 'run', '--task', TASK, '--bag', bag, '--write-key-file',
                       f'host-b={tmp_path / "old.key"}')
    assert code == 2 and 'old.key already exists' in err
    code, _, err = run(capsys, 'run', '--task', TASK, '--bag', bag, '--write-key-file', 'x')
    assert code == 2 and '--write-key-file x: expected ID=PATH' in err
    code, _, err = run(capsys, 'run', '--task', TASK, '--bag', bag, '--evaluators', '2',
                       '--write-key-file', f'evaluator-1-r1={tmp_path / "b.key"}')
    assert code == 2 and "evaluator-1-r1 is the name of one of this run's own" in err
    code, _, err = run(capsys, 'run', '--task', TASK, '--bag', bag, '--audit-fraction', '2')
    assert code == 2 and '--audit-fraction: expected a share from 0 to 1, got 2.0' in err
    assert not bag.exists()


def test_run_takes_the_shells_ros_domain_unless_told_otherwise():
    assert run_domain(None, {'ROS_DOMAIN_ID': '17'}) == (17, "the environment's ROS_DOMAIN_ID")
    assert run_domain(None, {})[0] == 0    # ROS 2's default when the variable is unset
    assert run_domain('auto', {'ROS_DOMAIN_ID': '17'})[0] is None    # a free one
    assert run_domain(5, {'ROS_DOMAIN_ID': '17'})[0] == 5
    with pytest.raises(UserError, match="ROS_DOMAIN_ID='x1' in the environment: expected 0 to"):
        run_domain(None, {'ROS_DOMAIN_ID': 'x1'})


@pytest.mark.system
@pytest.mark.parametrize('value', ['free', '233', '-1'])
def test_a_bad_domain_id_is_one_line(capsys, value):
    with pytest.raises(SystemExit) as stop:
        cli.main(['run', '--task', TASK, '--domain-id', value])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and f'expected "auto" or 0 to 232, got {value!r}' in err


@pytest.mark.system
@pytest.mark.parametrize('flag', ['--progress-every', '--start-timeout'])
@pytest.mark.parametrize('value', ['soon', '-5', 'nan'])
def test_a_bad_duration_is_one_line(capsys, flag, value):
    with pytest.raises(SystemExit) as stop:
        cli.main(['run', '--task', TASK, '--quiet', flag, value])
    err = capsys.readouterr().err
    assert stop.value.code == 2
    assert f'{flag}: expected seconds (a number >= 0), got {value!r}' in err


def test_a_quiet_run_says_a_progress_line_at_most_once_an_interval():
    throttle = ProgressThrottle(300.0)
    said = [seconds for seconds in (0.0, 10.0, 299.0, 300.0, 400.0, 650.0, 1000.0)
            if throttle.due(seconds)]
    assert said == [0.0, 300.0, 650.0, 1000.0]


@pytest.mark.system
def test_version_names_the_package_version():
    output = subprocess.run([sys.executable, '-m', 'hand_codesign.cli', '--version'],
                            capture_output=True, text=True, check=True).stdout
    assert output.startswith(f'hand-codesign {importlib.metadata.version("hand_codesign")}')
    if (ROOT / '.git').exists():   # a checkout: the commit too, as `git describe` gives it
        commit = subprocess.run(['git', 'rev-parse', '--short=7', 'HEAD'], cwd=ROOT,
                                capture_output=True, text=True, check=True).stdout.strip()
        assert f'(commit {commit}' in output


def run_with_stdout_unread(command):
    """Run a command whose stdout is a pipe that nobody reads any more (`command | head`)."""
    reading_end, writing_end = os.pipe()
    os.close(reading_end)
    try:
        return subprocess.run(command, stdout=writing_end, stderr=subprocess.PIPE, text=True,
                              timeout=120)
    finally:
        os.close(writing_end)


@pytest.mark.system
def test_a_reader_that_stops_reading_ends_the_verb_quietly():
    result = run_with_stdout_unread([sys.executable, '-m', 'hand_codesign.cli', 'reproduce',
                                     '--list'])
    assert result.returncode == 141 and result.stderr == ''


@pytest.mark.system
def test_a_broken_pipe_that_is_not_stdout_is_still_an_error():
    # stdout is read to the end here, so the pipe that broke must be another one
    result = subprocess.run(
        [sys.executable, '-c', 'from hand_codesign.errors import closed_stdout_status; '
                               'closed_stdout_status(BrokenPipeError("to a child"))'],
        capture_output=True, text=True, timeout=120)
    assert result.returncode == 1 and 'BrokenPipeError: to a child' in result.stderr
