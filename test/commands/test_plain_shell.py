"""
Every verb called as the README says, from a plain shell: no variable that `make` sets.

One tiny run (Task 5, 2 evaluators, 2 generations of 4 candidates on 2 worlds) is made with
`.venv/bin/hand-codesign run` in an environment that holds PATH and HOME only; every other
verb then reads its bag the same way, and replay also after `source .venv/bin/activate`; a
node started by hand (the recorder) works the same way.
"""

import json
import os
import pathlib
import shlex
import signal
import subprocess
import sys

from hand_codesign.core.contract import RECORDER_READY
import pytest
from test_system import free_domain

ROOT = pathlib.Path(__file__).resolve().parents[2]
TASK = ROOT / 'config' / 'tasks' / 'task5.yaml'
COMMAND = pathlib.Path(sys.prefix) / 'bin' / 'hand-codesign'
# what a login shell has; AMENT_PREFIX_PATH, CMAKE_PREFIX_PATH, ROS_* and the wheels'
# bootstrap guard are what `make` or a parent Python would have added
PLAIN = {name: os.environ[name] for name in ('PATH', 'HOME') if name in os.environ}


def plain(*arguments, timeout=120):
    """Run `.venv/bin/hand-codesign ARGUMENTS` in a plain environment; assert it succeeds."""
    process = subprocess.run([str(COMMAND), *map(str, arguments)], cwd=ROOT, env=PLAIN,
                             capture_output=True, text=True, timeout=timeout)
    assert process.returncode == 0, process.stdout + process.stderr
    assert 'Traceback' not in process.stderr, process.stderr
    return process.stdout


@pytest.fixture(scope='module')
def plain_bag(tmp_path_factory):
    """Return the bag folder of a tiny run made from a plain shell."""
    bag = tmp_path_factory.mktemp('plain') / 'run'
    plain('run', '--task', TASK, '--evaluators', 2, '--bag', bag, '--iterations', 2,
          '--population', 4, '--world-states', 2, '--seed', 3, '--quiet')
    assert json.loads((bag / 'result.json').read_text())['evaluations'] == 8
    return bag


def test_the_plain_environment_lacks_what_make_sets():
    assert COMMAND.exists()
    assert not any(name.startswith(('AMENT', 'CMAKE', 'ROS_', '_ROS')) for name in PLAIN)


@pytest.mark.system
def test_replay_to_mcap_by_path_and_after_activate(plain_bag, tmp_path):
    out = tmp_path / 'rollout.mcap'
    assert 'MCAP for Foxglove' in plain('replay', plain_bag, '--mcap', out)
    assert out.read_bytes()[:8] == b'\x89MCAP0\r\n'
    activated = tmp_path / 'activated.mcap'
    script = (f'source {shlex.quote(str(COMMAND.parent / "activate"))} && '
              f'hand-codesign replay {shlex.quote(str(plain_bag))} --mcap {activated}')
    process = subprocess.run(['bash', '-c', script], env=PLAIN, cwd=tmp_path,
                             capture_output=True, text=True, timeout=120)
    assert process.returncode == 0, process.stdout + process.stderr
    assert activated.exists()
    assert [path.name for path in tmp_path.iterdir() if path.name.startswith('.')] == []


@pytest.mark.system
def test_bag_verbs(plain_bag, tmp_path):
    assert 'report:' in plain('analyze', plain_bag, '--out', tmp_path / 'report')
    assert (tmp_path / 'report' / 'report.md').exists()
    assert 'recorded objectives' in plain('export', plain_bag, '--out', tmp_path / 'export')
    assert (tmp_path / 'export' / 'hand.urdf').exists()
    plain('robustness', plain_bag, '--samples', 2, '--workers', 1, '--out', tmp_path / 'rob')
    assert (tmp_path / 'rob' / 'worlds.csv').exists()
    assert 'already closed' in plain('recover', plain_bag)
    # nothing but the outputs: no staging folder left beside them
    assert sorted(path.name for path in tmp_path.iterdir()) == ['export', 'report', 'rob']


@pytest.mark.system
def test_verbs_without_a_bag():
    assert 'goals' in plain('check', TASK)
    assert 'all' in plain('reproduce', '--list').split()


@pytest.mark.system
def test_a_node_started_by_hand(tmp_path):
    # the recorder looks its message types up through ament_index_python
    bag = tmp_path / 'by-hand'
    recorder = subprocess.Popen(
        [str(COMMAND.parent / 'recorder'), '--ros-args', '-p', f'bag_path:={bag}'],
        env=dict(PLAIN, ROS_DOMAIN_ID=str(free_domain())), stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT, text=True)
    try:
        lines = []
        for line in recorder.stdout:
            lines.append(line)
            if RECORDER_READY in line:
                break
        recorder.send_signal(signal.SIGINT)
        output = ''.join(lines) + recorder.communicate(timeout=60)[0]
    finally:
        if recorder.poll() is None:
            recorder.kill()
    assert recorder.returncode == 0 and RECORDER_READY in output, output
    assert 'Traceback' not in output and list(bag.glob('*.mcap')), output
