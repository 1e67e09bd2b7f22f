"""
A node of a run ends with its run: when its runner dies, or when the run's optimizer is gone.

`hand-codesign run` (ros.runner) gives each process it starts the runner's pid through
RUNNER_VARIABLE. The node then asks the kernel to send it SIGTERM when the runner dies
(PR_SET_PDEATHSIG; it fires when the runner's thread that started the node ends, and the
runner starts every node from its main thread, whose end is the process's end; the ROS wheels'
bootstrapper re-executes Python with execve, which keeps the setting) and, as a second line, a
thread watches the runner's pid. SIGTERM ends a node as Ctrl-C does (rclpy's handler), so a
recorder closes its bag; a node still there GRACE seconds later kills itself. A process of
the run that is not ours (the discovery server) gets the same signal from `dies_with_me`.

An evaluator started by hand has no runner: OptimizerWatch tells it when the optimizer it
served has left the domain for good, and it gives the run up.
"""

import ctypes
import os
import signal
import threading
import time

RUNNER_VARIABLE = 'HAND_CODESIGN_RUNNER_PID'
PR_SET_PDEATHSIG = 1   # <linux/prctl.h>
WATCH_PERIOD = 0.5     # s between looks at the runner's pid
GRACE = 10.0           # s a node has to end after SIGTERM before it kills itself
# loaded here, not between fork and exec in a child (dies_with_me)
_LIBC = ctypes.CDLL(None, use_errno=True)


def runner_environment():
    """Return the variable that ties the processes the calling runner starts to its life."""
    return {RUNNER_VARIABLE: str(os.getpid())}


def follow_runner():
    """
    End this process when the runner that started it ends; return the runner's pid.

    Returns None, doing nothing, in a process no runner started (by hand, `ros2 run`). The
    variable is removed, so that processes this one starts do not follow the runner.
    """
    text = os.environ.pop(RUNNER_VARIABLE, '')
    if not text.isdigit():
        return None
    runner = int(text)
    _LIBC.prctl(PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0)
    # a runner that died before prctl: getppid() is no longer its pid, the watch ends us now
    threading.Thread(target=watch_runner, args=(runner,), daemon=True,
                     name='runner watch').start()
    return runner


def dies_with_me():
    """
    Return a preexec_fn for subprocess.Popen: the child gets SIGTERM when this process dies.

    Call Popen from the main thread (the signal follows the thread that forked) and before
    other threads start (a preexec_fn is not safe beside running threads).
    """
    parent = os.getpid()

    def arm():
        _LIBC.prctl(PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0)
        if os.getppid() != parent:   # the parent died before prctl: nobody will signal
            os._exit(1)
    return arm


def watch_runner(runner):
    """Wait while the runner is this process's parent; then end the process."""
    while os.getppid() == runner:
        time.sleep(WATCH_PERIOD)
    end_process()


def end_process():
    """Send this process SIGTERM; kill it if it is still there GRACE s later."""
    os.kill(os.getpid(), signal.SIGTERM)
    time.sleep(GRACE)
    os.kill(os.getpid(), signal.SIGKILL)


class OptimizerWatch:
    """
    Tell when the optimizer of a run has been gone for `timeout` seconds.

    `present(count)` is called about once a second with the number of the optimizer's
    publishers matched (of the candidates topic: a slow generation keeps it, a dead process
    loses it when its DDS lease ends). Only an optimizer seen once can be gone: an evaluator
    started before its run waits for it without limit. timeout 0: never gone.
    """

    def __init__(self, timeout, clock=time.monotonic):
        self.timeout = timeout
        self.clock = clock
        self.seen = False
        self.missing_since = None

    def gone(self, count):
        """Return True once the optimizer, seen before, has been missing for `timeout` s."""
        now = self.clock()
        if count > 0:
            self.seen, self.missing_since = True, None
            return False
        if not self.seen or self.timeout <= 0:
            return False
        if self.missing_since is None:
            self.missing_since = now
        return now - self.missing_since >= self.timeout


def watch_optimizer(node, topic, timeout):
    """
    Shut the node down once the optimizer publishing `topic` has been gone for timeout s.

    node: an rclpy Node, which logs why it gives the run up; the look is a timer of it.
    """
    watch = OptimizerWatch(timeout)

    def look():
        if watch.gone(node.count_publishers(topic)):
            node.get_logger().warning(
                f'the optimizer of the run has been gone for {timeout:g} s (parameter '
                'optimizer_timeout): giving the run up')
            node.context.try_shutdown()
    return node.create_timer(1.0, look)
