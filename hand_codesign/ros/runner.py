"""
The processes of a run on an isolated ROS 2 domain (`hand-codesign run`, hand_codesign.commands).

Starts the recorder, the evaluators and the optimizer side by side; the optimizer sends nothing
until the runner tells it that the recorder records (so the bag gets every candidate from the
first; the evaluators announce themselves only once the optimizer and the recorder are there);
relays the optimizer's progress; when the optimizer ends (or on Ctrl-C) stops the evaluators,
then the recorder, so that the bag holds every message and is closed properly.

While the optimizer runs, the recorder and the evaluators are supervised: when one exits,
core.run.supervision.Supervisor decides whether it is started again (a restarted recorder continues
the bag in its next file, a restarted evaluator serves under a new id and a unique node name)
or whether the run gives up and stops cleanly; this module only starts and stops processes.
A live view for Foxglove (`--live`), a rig's nodes (`--rig`) and the robot view (the best design
as robot_description and /tf, ros.robot_view_node) run beside them, unsupervised; a finished
run lets the robot view play the final best design's rollout before the recorder stops.

Evaluators on other hosts can join a run: start them with the run's ROS_DOMAIN_ID (printed at
the start) and a discovery range that reaches this host, e.g.
`ROS_DOMAIN_ID=17 ROS_AUTOMATIC_DISCOVERY_RANGE=SUBNET ros2 run hand_codesign evaluator`, or
through the run's discovery server (ros.discovery) where the network carries no multicast.

Keys (hand_codesign.core.run.signing): the optimizer gets the run's secret, each evaluator only
its own Credential, through a variable of the environment the child inherits, never on a
command line (any user can read command lines in `ps`; /proc/PID/environ only the same user
and root, like a 0600 file, without a file to leave behind) and never in the bag folder. The
recorder gets no key, and the nodes remove the variable from their environment once read.
"""

import collections
import contextlib
import fcntl
import os
import signal
import subprocess
import sys
import threading
import time

from hand_codesign.core.contract import EVALUATORS_READY
from hand_codesign.core.contract import LIVE_READY
from hand_codesign.core.contract import RECORDER_READY
from hand_codesign.core.contract import ROBOT_VIEW_READY
from hand_codesign.core.run.signing import CREDENTIAL_VARIABLE
from hand_codesign.core.run.signing import SECRET_VARIABLE
from hand_codesign.core.run.summary import PROGRESS_PREFIX
from hand_codesign.core.run.supervision import evaluator_role
from hand_codesign.core.run.supervision import node_name
from hand_codesign.core.run.supervision import RECORDER
from hand_codesign.core.run.supervision import Supervisor
from hand_codesign.errors import UserError
from hand_codesign.ros.discovery import start_profile
from hand_codesign.ros.lifeline import runner_environment

DOMAIN_IDS = range(1, 101)   # those a free pick (--domain-id auto) takes
MAX_DOMAIN_ID = 232   # the highest ROS_DOMAIN_ID ROS 2 accepts
STOP_TIMEOUT = 30.0
LAST_MESSAGES = 20   # the optimizer's last lines a quiet run that fails still prints
# s a finished run waits for the robot view to play its final best design's rollout (a rollout
# lasts a few simulated seconds, played in real time)
ROBOT_VIEW_WAIT = 30.0


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
    raise UserError(f'ROS domain {requested} is in use by another run of this host: choose '
                    'another with --domain-id ID, or a free one with --domain-id auto'
                    if requested is not None else 'no free ROS domain id on this host')


class System:
    """The processes of one run: recorder, evaluators and optimizer, kept alive while it runs."""

    def __init__(self, bag, domain_id, quiet=False, discovery=None, start_timeout=0.0,
                 live=None, keys=None, progress_every=None):
        """
        live: None, or the (host, port) the live view serves Foxglove on.

        quiet: say nothing but what `run` prints itself; progress_every: with quiet, still
        relay a generation's progress line, at most one every so many seconds (None: none).
        """
        self.bag = bag
        self.live = live
        self.live_view = self.robot_view = None
        self.quiet = quiet
        self.progress = None if progress_every is None else ProgressThrottle(progress_every)
        self.keys = keys  # core.run.signing.RunKeys, or None for an unsigned run
        inherited = {name: value for name, value in os.environ.items()
                     if name not in (SECRET_VARIABLE, CREDENTIAL_VARIABLE)}
        self.environment = dict(
            inherited, ROS_DOMAIN_ID=str(domain_id), PYTHONUNBUFFERED='1',
            ROS_AUTOMATIC_DISCOVERY_RANGE=os.environ.get('ROS_AUTOMATIC_DISCOVERY_RANGE',
                                                         'LOCALHOST'),
            AMENT_PREFIX_PATH=os.environ.get('AMENT_PREFIX_PATH', sys.prefix),
            RCUTILS_CONSOLE_OUTPUT_FORMAT='[{severity}] [{name}]: {message}',
            **runner_environment())   # no process of the run outlives the runner
        self.environment.update(start_profile(self.environment))
        self.discovery = discovery
        if discovery is not None:
            self.environment.update(discovery.environment())
        self.start_timeout = start_timeout
        self.supervisor = None
        self.recorder = None
        self.evaluators = {}   # role -> process
        self.rig_nodes = []
        self.rig_parameters = {}
        self.optimizer = None
        self.last_messages = collections.deque(maxlen=LAST_MESSAGES)
        self.relay = None

    def say(self, text):
        if not self.quiet:
            print(text, flush=True)

    def say_progress(self, text):
        """Print a generation's progress line unless quiet, or quiet but one is due."""
        if not self.quiet or (self.progress is not None and self.progress.due(time.monotonic())):
            print(text, flush=True)

    def node(self, module, parameters, key=None, remaps=(), **popen):
        command = [sys.executable, '-m', module, '--ros-args']
        for name, value in parameters.items():
            command += ['-p', f'{name}:={value}']
        for remap in remaps:
            command += ['-r', remap]
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

    def run(self, evaluators, optimizer_module, optimizer_parameters, rig='', start_signal=False):
        """
        Run recorder, evaluators and optimizer until the optimizer ends; return its code.

        rig: 'hardware' adds a rig evaluator (a rig joins the domain), 'sim' also a simulated
        rig (hand_codesign.ros.sim_rig_node); rig_parameters go to the simulated rig.
        start_signal: the optimizer takes ros.optimizer_node's parameter start_signal; it then
        starts beside the others and is told on its standard input when the recorder records.
        Otherwise it starts once the recorder records.
        """
        self.supervisor = Supervisor(evaluators, start_timeout=self.start_timeout)
        # every process logs into the bag folder from its start; the recorder writes beside
        (self.bag / 'logs').mkdir(parents=True, exist_ok=True)
        self.recorder = self.spawn_recorder()  # it finds a discovery server started later
        self.robot_view = self.spawn_robot_view()
        if self.live is not None:
            self.live_view = self.spawn_live_view()
        if self.discovery is not None:
            self.discovery.start(self.bag)
            self.say(self.discovery.join_instructions(self.environment['ROS_DOMAIN_ID']))
        for index in range(evaluators):
            self.start_evaluator(evaluator_role(index))
        self.start_rig(rig)
        if start_signal:
            self.start_optimizer(optimizer_module, dict(optimizer_parameters, start_signal=True))
        # the processes above start side by side; the optimizer sends once the recorder records
        self.wait_until_ready(self.recorder, RECORDER_READY, 'the recorder')
        self.wait_until_ready(self.robot_view, ROBOT_VIEW_READY, 'the robot view',
                              self.bag / 'logs' / 'robot_view.log')
        if self.live_view is not None:
            self.announce_live_view()
        if start_signal:
            with contextlib.suppress(BrokenPipeError):  # an optimizer that failed: supervise()
                self.optimizer.stdin.write('the recorder records\n')
                self.optimizer.stdin.flush()
        else:
            self.start_optimizer(optimizer_module, optimizer_parameters)
        code = self.supervise()
        self.relay.join(timeout=5.0)
        if code == 0:
            self.wait_for_robot_view()
        elif self.quiet and self.optimizer.returncode == code:
            # quiet hides the optimizer's messages; its reason for failing must still show
            for text in self.last_messages:
                print(text, file=sys.stderr, flush=True)
        self.stop_all()
        return code

    def start_optimizer(self, module, parameters):
        """Start the optimizer, its output relayed to the user."""
        self.optimizer = self.node(module, parameters, self.key_of(), stdin=subprocess.PIPE,
                                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        self.relay = threading.Thread(target=self.relay_optimizer, daemon=True)
        self.relay.start()

    def start_evaluator(self, role):
        """Start the process of an evaluator role, under the id the supervisor gives it."""
        evaluator_id = self.supervisor.started(role)
        log = open(self.bag / 'logs' / f'{evaluator_id}.log', 'w')
        self.evaluators[role] = self.node(
            'hand_codesign.ros.evaluator_node',
            {'evaluator_id': evaluator_id, 'subscribers_expected': 2}, self.key_of(evaluator_id),
            remaps=[f'__node:={node_name(evaluator_id)}'],
            stdout=log, stderr=subprocess.STDOUT)
        log.close()

    def start_rig(self, rig):
        """Start a rig evaluator ('hardware'), and with 'sim' the simulated rig as well."""
        nodes = []
        if rig:
            nodes.append(('rig_evaluator', 'hand_codesign.ros.rig_evaluator_node',
                          {'evaluator_id': 'rig_evaluator', 'subscribers_expected': 2},
                          self.key_of('rig_evaluator')))
        if rig == 'sim':
            nodes.append(('sim_rig', 'hand_codesign.ros.sim_rig_node',
                          dict(self.rig_parameters, subscribers_expected=2), None))
        for name, module, parameters, key in nodes:
            with open(self.bag / 'logs' / f'{name}.log', 'w') as log:
                self.rig_nodes.append(self.node(module, parameters, key, stdout=log,
                                                stderr=subprocess.STDOUT))

    def start_recorder(self):
        """Start the recorder and wait until it records; a restart continues the same bag."""
        self.recorder = self.spawn_recorder()
        self.wait_until_ready(self.recorder, RECORDER_READY, 'the recorder')

    def spawn_recorder(self):
        """Return a new recorder process; a restarted one continues the same bag."""
        restart = self.supervisor.started(RECORDER) != RECORDER
        parameters = {'bag_path': self.bag, 'continue_bag': restart}
        return self.node('hand_codesign.ros.recorder_node', parameters,
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)

    def spawn_robot_view(self):
        """Return the robot view (ros.robot_view_node): the best design as a robot model."""
        return self.node('hand_codesign.ros.robot_view_node', {}, stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True)

    def wait_for_robot_view(self):
        """Let the robot view play the final best design's rollout into the bag, then end."""
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.robot_view.wait(timeout=ROBOT_VIEW_WAIT)

    def spawn_live_view(self):
        host, port = self.live
        return self.node('hand_codesign.ros.live_node', {'host': host, 'port': port},
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)

    def announce_live_view(self):
        """Wait until the live view serves, then tell the user where."""
        line = self.wait_until_ready(self.live_view, LIVE_READY, 'the live view')
        address = line.split(LIVE_READY + ': ', 1)[-1].split()[0]
        self.say(f'live: {address} (in Foxglove: Open connection, Foxglove WebSocket; layout '
                 'config/foxglove_layout.json)')

    def wait_until_ready(self, process, ready, what, log=None):
        """
        Return the line of a starting process that says `ready`; then drain its output.

        log: a file that gets the process's output (else it is dropped once ready).
        """
        deadline = time.monotonic() + 60.0
        lines = []
        for line in process.stdout:
            lines.append(line)
            if ready in line or time.monotonic() > deadline:
                break
        if process.poll() is not None or not lines or ready not in lines[-1]:
            self.stop_all()
            raise UserError(f'{what} did not start:\n' + ''.join(lines[-20:]))
        threading.Thread(target=process.stdout.read if log is None else
                         lambda: copy_output(process.stdout, lines, log), daemon=True).start()
        return lines[-1]

    def relay_optimizer(self):
        """
        Relay the optimizer's output to the user and into logs/optimizer.log.

        Its last messages (not progress lines) are kept for a quiet run that fails.
        """
        with open(self.bag / 'logs' / 'optimizer.log', 'w') as log:
            for line in self.optimizer.stdout:
                log.write(line)
                log.flush()
                if EVALUATORS_READY in line:
                    self.supervisor.optimizer_ready()
                text = line.rstrip().replace('[INFO] [optimizer]: ', '')
                if text.startswith(PROGRESS_PREFIX):
                    self.say_progress(text)
                else:
                    self.last_messages.append(text)
                    self.say(text)

    def supervise(self):
        """Keep recorder and evaluators alive until the optimizer ends; return the run's code."""
        while self.optimizer.poll() is None:
            for role, process in self.processes():
                if process.poll() is not None:
                    self.supervisor.exited(role, process.returncode)
                    self.forget(role)
                    if self.supervisor.gave_up is None:
                        self.say(f'{role} exited (code {process.returncode}); restarting it')
            for role in self.supervisor.due():
                if role == RECORDER:
                    self.start_recorder()
                else:
                    self.start_evaluator(role)
            if self.supervisor.gave_up is not None:
                self.say(f'{self.supervisor.gave_up}; see the logs in {self.bag / "logs"}; '
                         'stopping')
                return 1
            time.sleep(0.2)
        if self.recorder is None:
            # the evaluators' history holds what the bag misses while they run: record it
            self.start_recorder()
        return self.optimizer.returncode

    def processes(self):
        """Return (role, process) of the running recorder and evaluators."""
        running = [(RECORDER, self.recorder)] if self.recorder is not None else []
        return running + list(self.evaluators.items())

    def forget(self, role):
        if role == RECORDER:
            self.recorder = None
        else:
            del self.evaluators[role]

    def stop_all(self):
        """Stop optimizer and evaluators first, the recorder last: it takes what is in flight."""
        stop([self.optimizer, self.robot_view] + list(self.evaluators.values())
             + self.rig_nodes)
        stop([self.recorder, self.live_view])
        if self.discovery is not None:
            self.discovery.stop()


class ProgressThrottle:
    """Whether a progress line is due: the first, then at most one every `interval` seconds."""

    def __init__(self, interval):
        self.interval = interval
        self.last = None

    def due(self, now):
        """Return True (and count it said) when a line may be said at `now` (seconds)."""
        if self.last is not None and now - self.last < self.interval:
            return False
        self.last = now
        return True


def copy_output(stream, lines, path):
    """Write lines already read, then the rest of a process's output stream, to path."""
    with open(path, 'w') as log:
        log.writelines(lines)
        for line in stream:
            log.write(line)
            log.flush()


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
