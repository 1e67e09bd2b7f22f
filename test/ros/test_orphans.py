"""
No process of a run outlives its runner (ros.lifeline), however the runner ends.

`hand-codesign run` is killed with SIGKILL (as the kernel kills for memory) during its
start-up and mid-run, and terminated with SIGTERM during its start-up; every process the run
started must be gone a few seconds later. bench/bench_orphans.py repeats this at many moments.
An evaluator started by hand gives a run up once its optimizer has been gone for
optimizer_timeout seconds.
"""

import os
import re
import signal
import socket
import subprocess
import sys
import time

from hand_codesign.ros.lifeline import OptimizerWatch
import pytest
from run_kills import describe
from run_kills import kill_run
from run_kills import ROOT
from run_kills import survivors
from run_kills import TASK
from test_system import free_domain

GRACE = 5.0  # s the processes of a killed run have to end


@pytest.mark.system
@pytest.mark.parametrize('after_seconds, after_line, how', [
    (0.0, None, signal.SIGKILL),              # while it starts its processes
    (0.7, None, signal.SIGKILL),              # while they import and start rclpy
    (None, 'generation 3/', signal.SIGKILL),  # mid-run
    (0.0, None, signal.SIGTERM),              # terminated while it starts its processes
])
def test_no_process_outlives_a_killed_runner(tmp_path, after_seconds, after_line, how):
    seen, output = kill_run(tmp_path / 'run', after_seconds, after_line, how)
    assert seen, output
    if after_line is not None:
        assert len(seen) >= 4, output   # recorder, two evaluators, optimizer
    left = survivors(seen, GRACE)
    assert not left, describe(left)


def free_udp_port():
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(('', 0))
        return probe.getsockname()[1]


@pytest.mark.system
def test_the_discovery_server_ends_with_its_runner(tmp_path):
    seen, output = kill_run(tmp_path / 'run', after_line='generation 2/',
                            extra=['--discovery-server', str(free_udp_port())])
    assert 'discovery server on port' in output
    assert len(seen) >= 5, output   # recorder, two evaluators, optimizer, discovery server
    left = survivors(seen, GRACE)
    assert not left, describe(left)


@pytest.mark.system
def test_an_evaluator_by_hand_gives_up_a_run_whose_optimizer_left(tmp_path):
    domain, key = free_domain(), tmp_path / 'by-hand.key'
    run = subprocess.Popen(
        [sys.executable, '-m', 'hand_codesign.cli', 'run', '--task', str(TASK),
         '--evaluators', '0', '--domain-id', str(domain), '--bag', str(tmp_path / 'run'),
         '--write-key-file', f'by-hand={key}', '--iterations', '1', '--population', '2',
         '--world-states', '1', '--quiet'],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    evaluator = None
    try:
        deadline = time.monotonic() + 60
        while not key.exists():
            assert run.poll() is None and time.monotonic() < deadline, run.stdout.read()
            time.sleep(0.05)
        evaluator = subprocess.Popen(
            [sys.executable, '-m', 'hand_codesign.ros.evaluator_node', '--ros-args',
             '-p', 'evaluator_id:=by-hand', '-p', f'key_file:={key}',
             '-p', 'optimizer_timeout:=1.0'],
            cwd=ROOT, env=dict(os.environ, ROS_DOMAIN_ID=str(domain)),
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        run_output, _ = run.communicate(timeout=120)
        assert run.returncode == 0, run_output
        output, _ = evaluator.communicate(timeout=30)
    finally:
        for process in (run, evaluator):
            if process is not None and process.poll() is None:
                process.kill()
    assert evaluator.returncode == 0, output
    assert 'has been gone for 1 s (parameter optimizer_timeout): giving the run up' in output
    assert re.search(r'by-hand published [1-9]\d* evaluations', output), output


class Clock:
    """A clock the test sets."""

    def __init__(self):
        self.now = 0.0

    def __call__(self):
        return self.now


def test_the_optimizer_watch():
    clock = Clock()
    watch = OptimizerWatch(60.0, clock)
    clock.now = 500.0
    assert not watch.gone(0)          # never saw an optimizer: waits for one without limit
    assert not watch.gone(1)
    clock.now = 530.0
    assert not watch.gone(0)          # gone since 530
    clock.now = 589.0
    assert not watch.gone(0)
    clock.now = 590.0
    assert watch.gone(0)
    assert not watch.gone(1)          # back (a resumed run): the count starts again
    clock.now = 640.0
    assert not watch.gone(0)
    assert not OptimizerWatch(0.0, clock).gone(0)
