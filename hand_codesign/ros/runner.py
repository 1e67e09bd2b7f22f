"""
`hand-codesign run`: the whole system as separate processes on an isolated ROS 2 domain.

Starts the recorder first and waits until it is ready, then the evaluators and the optimizer;
relays the optimizer's progress; when the optimizer ends (or on Ctrl-C) stops the evaluators,
then the recorder, so that the bag holds every message and is closed properly.

Evaluators on other hosts can join a run: start them with the run's ROS_DOMAIN_ID (printed at
the start) and a discovery range that reaches this host, e.g.
`ROS_DOMAIN_ID=17 ROS_AUTOMATIC_DISCOVERY_RANGE=SUBNET ros2 run hand_codesign evaluator`.
"""

import contextlib
import fcntl
import json
import os
import pathlib
import signal
import subprocess
import sys
import threading
import time

from hand_codesign.core.runs import load_run_task
from hand_codesign.core.task import TaskError
from hand_codesign.errors import UserError

READY_LINE = 'recorder ready'
DOMAIN_IDS = range(1, 101)
STOP_TIMEOUT = 30.0


def run_command(arguments):
    """Run a co-design as processes; return the exit code."""
    task = check_arguments(arguments)
    bag = pathlib.Path(arguments.bag or default_bag_path(task.name)).resolve()
    if bag.exists():
        raise UserError(f'--bag {bag}: already exists; choose a new path')
    if bag.suffix == '.mcap':
        raise UserError(f'--bag {bag}: give a folder (the run writes its bag, result.json and '
                        'logs there), not a .mcap file')
    with claimed_domain(arguments.domain_id) as domain_id:
        system = System(bag, domain_id, quiet=arguments.quiet)
        say = system.say
        source = arguments.task or f'resumed from {arguments.resume}'
        say(f'run: task {task.name} ({source}), evaluators: {arguments.evaluators}, '
            f'ROS_DOMAIN_ID={domain_id}, bag {bag}')
        try:
            with termination_as_interrupt():
                code = system.run(arguments, task)
        except KeyboardInterrupt:
            say('interrupted: stopping the evaluators and closing the bag')
            system.stop_all()
            print(f'bag (interrupted run): {bag}')
            return 130
        finally:
            system.stop_all()
    if code != 0:
        print(f'bag: {bag}', file=sys.stderr)
        return code
    print(f'bag: {bag}')
    print(f'best design: {best_design_line(bag / "result.json")}')
    return 0


@contextlib.contextmanager
def termination_as_interrupt():
    """Treat SIGTERM and SIGHUP like Ctrl-C, so that the processes of the run are stopped."""
    def interrupt(signal_number, frame):
        raise KeyboardInterrupt

    previous = {number: signal.signal(number, interrupt)
                for number in (signal.SIGTERM, signal.SIGHUP)}
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)


def check_arguments(arguments):
    """Return the run's Task, or raise UserError naming the bad flag or file."""
    if arguments.resume:
        return resumed_task(arguments)
    if not arguments.task:
        raise UserError('--task FILE is required (e.g. config/tasks/task5.yaml)')
    if arguments.evaluators < 0:
        raise UserError(f'--evaluators: expected 0 or more, got {arguments.evaluators}')
    for flag in ('iterations', 'popsize', 'world_states'):
        value = getattr(arguments, flag)
        if value is not None and value < 1:
            raise UserError(f'--{flag.replace("_", "-")}: expected a positive number, '
                            f'got {value}')
    try:
        return load_run_task(arguments.task, arguments.seed, arguments.iterations,
                             arguments.popsize, arguments.world_states)
    except TaskError as error:
        raise UserError(str(error))


def resumed_task(arguments):
    """Return the Task of the interrupted run in --resume's bag; it fixes task and budget."""
    given = [flag for flag in ('task', 'seed', 'iterations', 'popsize', 'world_states')
             if getattr(arguments, flag) is not None]
    if given:
        raise UserError('--resume takes the task, seed and budget from the bag; drop '
                        + ', '.join('--' + flag.replace('_', '-') for flag in given))
    from hand_codesign.analysis.resume import resume_point
    point = resume_point(arguments.resume)
    if not arguments.quiet:
        print(point.describe(), flush=True)
    return point.task


def default_bag_path(task_name):
    return f'bags/{task_name}-{time.strftime("%Y%m%d-%H%M%S")}'


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


def best_design_line(result_file):
    result = json.loads(result_file.read_text())
    objectives = ', '.join(f'{name} {value:.4g}' for name, value in result['objectives'].items())
    return (f'candidate {result["best_candidate_id"]} of generation {result["generation"]}, '
            f'fitness {result["fitness"]:.4g} ({objectives}); '
            f'{len(result["design"])} parameters in {result_file}')


class System:
    """The processes of one run: recorder, evaluators and optimizer."""

    def __init__(self, bag, domain_id, quiet=False):
        self.bag = bag
        self.quiet = quiet
        self.environment = dict(
            os.environ, ROS_DOMAIN_ID=str(domain_id), PYTHONUNBUFFERED='1',
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

    def node(self, module, parameters, **popen):
        command = [sys.executable, '-m', f'hand_codesign.ros.{module}', '--ros-args']
        for name, value in parameters.items():
            command += ['-p', f'{name}:={value}']
        # a session of its own: the terminal's Ctrl-C reaches only the runner, which then
        # stops the processes in the order that keeps the bag complete
        return subprocess.Popen(command, env=self.environment, start_new_session=True,
                                **popen)

    def run(self, arguments, task):
        # Every process starts at once (their imports and DDS discovery overlap); the
        # optimizer sends nothing before the recorder and the evaluators have matched.
        self.recorder = self.node('recorder_node', {'bag_path': self.bag},
                                  stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        # The recorder creates the bag folder; the logs move into it once it is ready.
        logs = self.bag.with_name(self.bag.name + '.logs')
        logs.mkdir(parents=True, exist_ok=True)
        for index in range(arguments.evaluators):
            log = open(logs / f'evaluator-{index}.log', 'w')
            self.evaluators.append(self.node(
                'evaluator_node', {'evaluator_id': f'evaluator-{index}',
                                   'subscribers_expected': 2},
                stdout=log, stderr=subprocess.STDOUT))
        parameters = {
            'evaluators_expected': max(1, arguments.evaluators), 'subscribers_expected': 1,
            'result_file': self.bag / 'result.json'}
        if arguments.resume:
            parameters['resume_bag'] = pathlib.Path(arguments.resume).resolve()
        else:
            parameters.update({
                'task_file': pathlib.Path(arguments.task).resolve(), 'seed': task.seed,
                'iterations': task.iterations, 'population': task.population,
                'world_states': task.num_world_states})
        self.optimizer = self.node('optimizer_node', parameters, stdout=subprocess.PIPE,
                                   stderr=subprocess.STDOUT, text=True)
        self.wait_for_recorder()
        logs.rename(self.bag / 'logs')
        relay = threading.Thread(target=self.relay_optimizer, daemon=True)
        relay.start()
        code = self.wait_for_optimizer()
        relay.join(timeout=5.0)
        self.stop_all()
        return code

    def wait_for_recorder(self):
        deadline = time.monotonic() + 60.0
        lines = []
        for line in self.recorder.stdout:
            lines.append(line)
            if READY_LINE in line:
                break
            if time.monotonic() > deadline:
                break
        if self.recorder.poll() is not None or not any(READY_LINE in x for x in lines):
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
