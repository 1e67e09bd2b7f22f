"""
The processes of a run on an isolated ROS 2 domain (`hand-codesign run`, hand_codesign.commands).

Starts the recorder first and waits until it is ready, then the evaluators and the optimizer;
relays the optimizer's progress; when the optimizer ends (or on Ctrl-C) stops the evaluators,
then the recorder, so that the bag holds every message and is closed properly.

Evaluators on other hosts can join a run: start them with the run's ROS_DOMAIN_ID (printed at
the start) and a discovery range that reaches this host, e.g.
`ROS_DOMAIN_ID=17 ROS_AUTOMATIC_DISCOVERY_RANGE=SUBNET ros2 run hand_codesign evaluator`.

Keys (hand_codesign.core.signing): the optimizer gets the run's secret, each evaluator only
its own Credential, through a variable of the environment the child inherits, never on a
command line (any user can read command lines in `ps`; /proc/PID/environ only the same user
and root, like a 0600 file, without a file to leave behind) and never in the bag folder. The
recorder gets no key, and the nodes remove the variable from their environment once read.
"""

import contextlib
import fcntl
import os
import signal
import subprocess
import sys
import threading
import time

from hand_codesign.core.contract import RECORDER_READY
from hand_codesign.core.signing import CREDENTIAL_VARIABLE
from hand_codesign.core.signing import SECRET_VARIABLE
from hand_codesign.errors import UserError

DOMAIN_IDS = range(1, 101)
STOP_TIMEOUT = 30.0


@contextlib.contextmanager
def claimed_domain(requested):
    """Hold a ROS_DOMAIN_ID no other run of this host holds, for the run's duration."""
    candidates = [requested] if requested is not None else list(DOMAIN_IDS)
    for domain_id in candidates:
        lock = open(f'/tmp/hand_codesign-domain-{domain_id}.lock', 'w')
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            lock.close()
            continue
        try:
            yield domain_id
        finally:
            lock.close()
        return
    raise UserError(f'ROS domain {requested} is in use by another run of this host'
                    if requested is not None else 'no free ROS domain id on this host')


class System:
    """The processes of one run: recorder, evaluators and optimizer."""

    def __init__(self, bag, domain_id, quiet=False, keys=None):
        self.bag = bag
        self.quiet = quiet
        self.keys = keys  # core.signing.RunKeys, or None for an unsigned run
        inherited = {name: value for name, value in os.environ.items()
                     if name not in (SECRET_VARIABLE, CREDENTIAL_VARIABLE)}
        self.environment = dict(
            inherited, ROS_DOMAIN_ID=str(domain_id), PYTHONUNBUFFERED='1',
            ROS_AUTOMATIC_DISCOVERY_RANGE=os.environ.get('ROS_AUTOMATIC_DISCOVERY_RANGE',
                                                         'LOCALHOST'),
            AMENT_PREFIX_PATH=os.environ.get('AMENT_PREFIX_PATH', sys.prefix),
            RCUTILS_CONSOLE_OUTPUT_FORMAT='[{severity}] [{name}]: {message}')
        self.recorder = None
        self.evaluators = []
        self.optimizer = None

    def say(self, text):
        if not self.quiet:
            print(text, flush=True)

    def node(self, module, parameters, key=None, **popen):
        command = [sys.executable, '-m', module, '--ros-args']
        for name, value in parameters.items():
            command += ['-p', f'{name}:={value}']
        # a session of its own: the terminal's Ctrl-C reaches only the runner, which then
        # stops the processes in the order that keeps the bag complete
        environment = dict(self.environment, **(key or {}))
        return subprocess.Popen(command, env=environment, start_new_session=True, **popen)

    def key_of(self, evaluator_id=None):
        """Return the key variable of an evaluator, or with None the optimizer's secret."""
        if self.keys is None:
            return None
        if evaluator_id is None:
            return {SECRET_VARIABLE: self.keys.secret.hex()}
        return {CREDENTIAL_VARIABLE: self.keys.credential(evaluator_id).text()}

    def run(self, evaluators, optimizer_module, optimizer_parameters):
        """Run recorder, evaluators and optimizer until the optimizer ends; return its code."""
        self.start_recorder()
        logs = self.bag / 'logs'
        logs.mkdir()
        for index in range(evaluators):
            log = open(logs / f'evaluator-{index}.log', 'w')
            self.evaluators.append(self.node(
                'hand_codesign.ros.evaluator_node', {'evaluator_id': f'evaluator-{index}',
                                                     'subscribers_expected': 2},
                self.key_of(f'evaluator-{index}'), stdout=log, stderr=subprocess.STDOUT))
        self.optimizer = self.node(optimizer_module, optimizer_parameters, self.key_of(),
                                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        relay = threading.Thread(target=self.relay_optimizer, daemon=True)
        relay.start()
        code = self.wait_for_optimizer()
        relay.join(timeout=5.0)
        self.stop_all()
        return code

    def start_recorder(self):
        self.recorder = self.node('hand_codesign.ros.recorder_node', {'bag_path': self.bag},
                                  stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        deadline = time.monotonic() + 60.0
        lines = []
        for line in self.recorder.stdout:
            lines.append(line)
            if RECORDER_READY in line:
                break
            if time.monotonic() > deadline:
                break
        if self.recorder.poll() is not None or not any(RECORDER_READY in x for x in lines):
            self.stop_all()
            raise UserError('the recorder did not start:\n' + ''.join(lines[-20:]))
        threading.Thread(target=self.recorder.stdout.read, daemon=True).start()

    def relay_optimizer(self):
        for line in self.optimizer.stdout:
            self.say(line.rstrip().replace('[INFO] [optimizer]: ', ''))

    def wait_for_optimizer(self):
        while self.optimizer.poll() is None:
            if self.recorder.poll() is not None:
                self.say(f'the recorder exited (code {self.recorder.returncode}); stopping')
                return 1
            if self.evaluators and all(p.poll() is not None for p in self.evaluators):
                self.say('every evaluator exited: see the logs in '
                         f'{self.bag / "logs"}; stopping')
                return 1
            time.sleep(0.2)
        return self.optimizer.returncode

    def stop_all(self):
        """Stop optimizer and evaluators first, the recorder last: it takes what is in flight."""
        stop([self.optimizer] + self.evaluators)
        stop([self.recorder])


def stop(processes):
    """Send SIGINT to running processes and wait; kill those that do not end in time."""
    running = [p for p in processes if p is not None and p.poll() is None]
    for process in running:
        process.send_signal(signal.SIGINT)
    deadline = time.monotonic() + STOP_TIMEOUT
    for process in running:
        try:
            process.wait(timeout=max(0.1, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
