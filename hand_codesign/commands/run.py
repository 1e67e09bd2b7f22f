"""
`hand-codesign run`: a co-design as separate processes, fresh or resumed from a bag.

This command checks the flags, loads the run's task (from the task file, or for `--resume`
from the bag through hand_codesign.analysis.resume), draws the run's secret (core.run.signing)
and writes the key files asked for, lets hand_codesign.ros.runner start and stop the
processes, and prints where the bag and the best design are.
"""

import contextlib
import json
import os
import pathlib
import signal
import sys
import time

from hand_codesign.core.run.runs import engines_text
from hand_codesign.core.run.runs import load_run_task
from hand_codesign.core.run.signing import new_secret
from hand_codesign.core.run.signing import RunKeys
from hand_codesign.core.run.supervision import evaluator_role
from hand_codesign.core.run.supervision import serves_role
from hand_codesign.core.task import TaskError
from hand_codesign.errors import UserError
from hand_codesign.ros.discovery import DiscoveryServer
from hand_codesign.ros.runner import claimed_domain
from hand_codesign.ros.runner import MAX_DOMAIN_ID
from hand_codesign.ros.runner import System

OPTIMIZER_MODULE = 'hand_codesign.commands.optimizer'
# Evaluators of the run start in 0.3 to 2.7 s and are restarted when they die (core.
# supervision); a run whose evaluators have not joined after this long will not get them.
DEFAULT_START_TIMEOUT = 300.0


def run_command(arguments):
    """Run a co-design as processes; return the exit code."""
    task = check_arguments(arguments)
    bag = pathlib.Path(arguments.bag or default_bag_path(task.name)).resolve()
    if bag.exists():
        raise UserError(f'--bag {bag}: already exists; choose a new path')
    if bag.suffix == '.mcap':
        raise UserError(f'--bag {bag}: give a folder (the run writes its bag, result.json and '
                        'logs there), not a .mcap file')
    key_files = key_file_requests(arguments.write_key_file, bag, own_roles(arguments))
    keys = RunKeys(new_secret())
    discovery = (DiscoveryServer(arguments.discovery_server)
                 if arguments.discovery_server is not None else None)
    requested_domain, domain_source = run_domain(arguments.domain_id)
    with claimed_domain(requested_domain) as domain_id:
        live = None if arguments.live is None else (arguments.live_host, arguments.live)
        system = System(bag, domain_id, quiet=arguments.quiet, discovery=discovery,
                        start_timeout=start_timeout(arguments), live=live, keys=keys,
                        progress_every=arguments.progress_every)
        say = system.say
        for evaluator_id, path in key_files:
            write_key_file(path, keys.credential(evaluator_id).text())
            say(f'key of evaluator {evaluator_id}: {path} (start it with ROS_DOMAIN_ID='
                f'{domain_id} and -p key_file:={path})')
        source = arguments.task or f'resumed from {arguments.resume}'
        say(f'run: task {task.name} ({source}), evaluators: {arguments.evaluators}, '
            f'ROS_DOMAIN_ID={domain_id} ({domain_source}), bag {bag}')
        try:
            with termination_as_interrupt():
                system.rig_parameters = rig_parameters(arguments)
                code = system.run(arguments.evaluators, OPTIMIZER_MODULE,
                                  optimizer_parameters(arguments, task, bag), arguments.rig,
                                  start_signal=True)
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


def run_domain(option, environment=os.environ):
    """
    Return (ROS domain id to hold, None for a free one; how it was chosen, for the user).

    option: --domain-id, 'auto', an int or None. None takes the environment's ROS_DOMAIN_ID,
    as every ROS 2 tool does, so that `ros2 topic echo` in the user's shell sees the run.
    """
    if option == 'auto':
        return None, 'a free one of this host: --domain-id auto'
    if option is not None:
        return option, '--domain-id'
    text = environment.get('ROS_DOMAIN_ID', '').strip()
    if not text:
        return 0, "ROS_DOMAIN_ID is not set: ROS 2's default; --domain-id auto picks a free one"
    if not text.isdigit() or int(text) > MAX_DOMAIN_ID:
        raise UserError(f'ROS_DOMAIN_ID={text!r} in the environment: expected 0 to '
                        f'{MAX_DOMAIN_ID} (or run with --domain-id ID or --domain-id auto)')
    return int(text), "the environment's ROS_DOMAIN_ID"


def start_timeout(arguments):
    """Return the seconds the evaluators have to join: --start-timeout, else by --evaluators."""
    if arguments.start_timeout is not None:
        return arguments.start_timeout
    return DEFAULT_START_TIMEOUT if arguments.evaluators > 0 else 0.0


def key_file_requests(requests, bag, own=()):
    """
    Return [(evaluator id, path)] of --write-key-file ID=PATH; UserError if unusable.

    own: the roles of the run's own evaluators, whose names another host may not take.
    """
    chosen = []
    for request in requests:
        evaluator_id, _, path = request.partition('=')
        if not evaluator_id or not path:
            raise UserError(f'--write-key-file {request}: expected ID=PATH, e.g. '
                            'host-b=/home/me/host-b.key')
        if serves_role(evaluator_id, own):
            raise UserError(f'--write-key-file {request}: {evaluator_id} is the name of one of '
                            "this run's own evaluators; choose another id for the other host")
        path = pathlib.Path(path).resolve()
        if path == bag or bag in path.parents:
            raise UserError(f'--write-key-file {request}: {path} is inside the bag folder, '
                            'which must hold nothing secret; choose a path outside it')
        if path.exists():
            raise UserError(f'--write-key-file {request}: {path} already exists; keys of an '
                            'earlier run do not fit this one, choose a new path')
        chosen.append((evaluator_id, path))
    return chosen


def write_key_file(path, text):
    """Write a key file that only its owner can read (created with mode 0600)."""
    descriptor = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    with os.fdopen(descriptor, 'w') as stream:
        stream.write(text + '\n')


def own_roles(arguments):
    """Return the roles of the evaluators this run starts itself (core.run.supervision)."""
    return [evaluator_role(index) for index in range(arguments.evaluators)]


def optimizer_parameters(arguments, task, bag):
    """Return the optimizer node's parameters for this run."""
    parameters = {
        'evaluators_expected': max(1, arguments.evaluators + bool(arguments.rig)),
        'subscribers_expected': 1,
        'result_file': bag / 'result.json'}
    if arguments.evaluators:  # rcl refuses an empty value on the command line
        parameters['own_evaluators'] = ','.join(own_roles(arguments))
    if getattr(arguments, 'audit_fraction', None) is not None:
        parameters['audit_fraction'] = arguments.audit_fraction
    if arguments.resume:
        parameters['resume_bag'] = pathlib.Path(arguments.resume).resolve()
        if arguments.iterations:  # continue for more generations than the run's own
            parameters['iterations'] = arguments.iterations
    else:
        parameters.update({
            'task_file': pathlib.Path(arguments.task).resolve(), 'seed': task.seed,
            'iterations': task.iterations, 'population': task.population,
            'world_states': task.num_world_states, 'engine': engines_text(task)})
    return parameters


def rig_parameters(arguments):
    """Return the simulated rig's parameters from the --rig-* flags."""
    if arguments.rig_rate < 0 or not 0 <= arguments.rig_phase <= 1:
        raise UserError(f'--rig-rate {arguments.rig_rate} / --rig-phase {arguments.rig_phase}: '
                        'expected a rate >= 0 (0: every physics step) and a phase in [0, 1]')
    parameters = {'rate': float(arguments.rig_rate), 'phase': float(arguments.rig_phase)}
    if getattr(arguments, 'rig_engine', None):  # rcl refuses an empty value
        parameters['engine'] = arguments.rig_engine
    return parameters


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
    if arguments.live is not None and not 0 <= arguments.live <= 65535:
        raise UserError(f'--live: expected a TCP port from 0 (any free one) to 65535, got '
                        f'{arguments.live}')
    for flag in ('iterations', 'population', 'world_states'):
        value = getattr(arguments, flag)
        if value is not None and value < 1:
            raise UserError(f'--{flag.replace("_", "-")}: expected a positive number, '
                            f'got {value}')
    if arguments.resume:
        return resumed_task(arguments)
    if not arguments.task:
        raise UserError('--task FILE is required (e.g. config/tasks/task5.yaml)')
    if arguments.evaluators < 0:
        raise UserError(f'--evaluators: expected 0 or more, got {arguments.evaluators}')
    if arguments.discovery_server is not None and not 0 < arguments.discovery_server < 65536:
        raise UserError(f'--discovery-server: expected a UDP port from 1 to 65535, got '
                        f'{arguments.discovery_server}')
    fraction = getattr(arguments, 'audit_fraction', None)
    if fraction is not None and not 0.0 <= fraction <= 1.0:
        raise UserError(f'--audit-fraction: expected a share from 0 to 1, got {fraction}')
    try:
        return load_run_task(arguments.task, arguments.seed, arguments.iterations,
                             arguments.population, arguments.world_states,
                             getattr(arguments, 'engine', None))
    except TaskError as error:
        raise UserError(str(error))


def resumed_task(arguments):
    """
    Return the Task of the run in --resume's bag; it fixes task, seed and budget.

    With --iterations, more generations than the run's own: a finished run continues.
    """
    given = [flag for flag in ('task', 'seed', 'population', 'world_states', 'engine')
             if getattr(arguments, flag, None) is not None]
    if given:
        raise UserError('--resume takes the task, seed and budget from the bag; drop '
                        + ', '.join('--' + flag.replace('_', '-') for flag in given)
                        + ' (--iterations continues the run for more generations)')
    from hand_codesign.analysis.resume import resume_point
    point = resume_point(arguments.resume, arguments.iterations or 0)
    if not arguments.quiet:
        print(point.describe(), flush=True)
    return point.task


def default_bag_path(task_name):
    """Return bags/<task>-<date>-<time>, where a run writes when --bag is not given."""
    return f'bags/{task_name}-{time.strftime("%Y%m%d-%H%M%S")}'


def best_design_line(result_file):
    """Return the line telling the user about the best design of a run's result.json."""
    result = json.loads(result_file.read_text())
    objectives = ', '.join(f'{name} {value:.4g}' for name, value in result['objectives'].items())
    origin = f'generation {result["generation"]}'
    checked = [entry for entry in result.get('final_check', ())
               if entry['candidate_id'] == result['best_candidate_id']]
    if checked:  # a resampled run: the design of a generation, scored on the fixed worlds
        origin = (f'the final check (candidate {checked[0]["repeats"]} of generation '
                  f'{checked[0]["generation"]} on the fixed worlds)')
    return (f'candidate {result["best_candidate_id"]} of {origin}, '
            f'fitness {result["fitness"]:.4g} ({objectives}); '
            f'{len(result["design"])} parameters in {result_file}')
