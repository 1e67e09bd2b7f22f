"""
Kill `hand-codesign run` at a chosen moment and see which of its processes are still there.

Shared by test/ros/test_orphans.py (a few moments) and bench/bench_orphans.py (a sweep). The run's
processes are found two ways, so that none escapes: the runner's descendants, looked at every
POLL seconds while it lives, and every process whose start environment names the runner
(ros.lifeline.RUNNER_VARIABLE: a node removes it from os.environ, while /proc/PID/environ keeps
what the process started with), which also finds a process forked in the last instant.
"""

import contextlib
import pathlib
import signal
import subprocess
import sys
import threading
import time

from hand_codesign.ros.lifeline import RUNNER_VARIABLE
import psutil

ROOT = pathlib.Path(__file__).resolve().parents[2]
TASK = ROOT / 'config' / 'tasks' / 'task5.yaml'
# long enough to be killed mid-run: about 40 generations per 10 s on 2 cores
BUDGET = ['--iterations', '400', '--population', '6', '--world-states', '2', '--seed', '3']
POLL = 0.02


def processes_of(runner_pid):
    """Return the processes whose start environment names runner_pid as their runner."""
    found = set()
    for process in psutil.process_iter():
        with contextlib.suppress(psutil.Error):
            if process.environ().get(RUNNER_VARIABLE) == str(runner_pid):
                found.add(process)
    return found


def kill_run(bag, after_seconds=None, after_line=None, how=signal.SIGKILL, timeout=60.0,
             extra=()):
    """
    Start a run, signal its runner; return (every process of the run seen, the output).

    The signal `how` goes after_seconds s after the run's first process started, or once a
    line of the runner's output contains after_line. extra: more arguments of `run`.
    """
    runner = subprocess.Popen(
        [sys.executable, '-m', 'hand_codesign.cli', 'run', '--task', str(TASK),
         '--evaluators', '2', '--bag', str(bag), *BUDGET, *extra],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    lines = []
    threading.Thread(target=lambda: lines.extend(runner.stdout), daemon=True).start()
    seen = set()
    started, first_child = time.monotonic(), None
    while True:
        with contextlib.suppress(psutil.Error):
            seen.update(psutil.Process(runner.pid).children(recursive=True))
        if seen and first_child is None:
            first_child = time.monotonic()
        if after_seconds is not None and first_child is not None and (
                time.monotonic() - first_child >= after_seconds):
            break
        if after_line is not None and any(after_line in line for line in lines):
            break
        assert runner.poll() is None, ''.join(lines)
        assert time.monotonic() - started < timeout, ''.join(lines)
        time.sleep(POLL)
    runner.send_signal(how)
    runner.wait(timeout=120)
    seen |= processes_of(runner.pid)
    return seen, ''.join(lines)


def survivors(processes, timeout):
    """Wait up to timeout s for the processes to end; return those still running."""
    deadline = time.monotonic() + timeout
    while True:
        alive = [process for process in processes if running(process)]
        if not alive or time.monotonic() > deadline:
            return alive
        time.sleep(0.1)


def running(process):
    """Return whether a process runs (an orphan that ended but is not reaped yet does not)."""
    try:
        return process.is_running() and process.status() != psutil.STATUS_ZOMBIE
    except psutil.Error:
        return False


def describe(processes):
    """Return one line per process: pid and command line."""
    lines = []
    for process in processes:
        with contextlib.suppress(psutil.Error):
            lines.append(f'{process.pid}: {" ".join(process.cmdline())[:150]}')
    return '\n'.join(lines)
