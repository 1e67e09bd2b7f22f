"""
The whole system as a user runs it: `hand-codesign run` with real processes over DDS.

Each run uses its own ROS domain. The runs are small (Task 5, a few candidates and worlds)
so that the properties are shown in seconds: bit-identical summaries with 1 and 3
evaluators, a run that survives an evaluator killed with SIGKILL, a bag holding every
message, a run undisturbed by a forger without a key (and whose keys stay out of command
lines, bag and logs), and a lying evaluator with a key caught by an audit.
"""

import contextlib
import json
import os
import pathlib
import signal
import socket
import subprocess
import sys
import threading
import time

from hand_codesign.analysis.trust import trust_counts
from hand_codesign.bag.reader import read_run
from hand_codesign.core.run.signing import new_secret
from hand_codesign.core.run.signing import RunKeys
from hand_codesign.ros.runner import claimed_domain
from hand_codesign.ros.runner import System
from intruder import FORGED_SUMMARIES
import numpy as np
import psutil
import pytest

pytestmark = pytest.mark.system

ROOT = pathlib.Path(__file__).resolve().parents[2]
HERE = ROOT / 'test' / 'ros'
TASK = ROOT / 'config' / 'tasks' / 'task5.yaml'
# for a process that starts before a run: it announces itself often (the file says why)
ANNOUNCE_OFTEN = HERE / 'announce_long.xml'
BUDGET = ['--iterations', '3', '--population', '6', '--world-states', '3', '--seed', '7']
SUMMARY_FIELDS = ['generation', 'best', 'median', 'worst', 'pareto_front',
                  'best_candidate_id', 'best_objectives', 'best_fitness', 'best_genome',
                  'evaluations', 'final']


def free_domain():
    """Return a ROS domain that no run of this host holds right now (the runner's own locks)."""
    with claimed_domain(None) as domain_id:
        return domain_id


def start_run(bag, evaluators, extra=(), budget=BUDGET, domain=None, task=TASK):
    # `--domain-id auto`: the runner claims a free domain itself, also when other test
    # sessions run on this host at the same time
    chosen = ['--domain-id', str(domain) if domain is not None else 'auto']
    command = [sys.executable, '-m', 'hand_codesign.cli', 'run', '--task', str(task),
               '--evaluators', str(evaluators), '--bag', str(bag), *chosen, *budget, *extra]
    return subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)


def finish(process, timeout=240):
    output, _ = process.communicate(timeout=timeout)
    assert process.returncode == 0, output
    return output


def run(bag, evaluators, extra=()):
    return finish(start_run(bag, evaluators, extra))


def summaries(bag):
    run_id = json.loads((bag / 'result.json').read_text())['run_id']
    table = read_run(bag, run_id=run_id).generation_summaries
    return [{name: np.asarray(table[name][row]).tolist() for name in SUMMARY_FIELDS}
            for row in range(len(table))]


def assert_same_with_two_evaluators(bag, task, folder, budget):
    """Run `task` again with 2 evaluators: the same generations as `bag`, both evaluators used."""
    two = folder / 'two'
    finish(start_run(two, 2, budget=budget, task=task))
    assert summaries(two) == summaries(bag)
    assert len(set(read_run(two).evaluations['evaluator_id'])) >= 2


@pytest.fixture(scope='module')
def one_evaluator_run(tmp_path_factory):
    bag = tmp_path_factory.mktemp('runs') / 'one'
    output = run(bag, 1)
    return bag, output


def test_run_prints_bag_and_best_design(one_evaluator_run):
    bag, output = one_evaluator_run
    assert f'bag: {bag}' in output
    assert 'best design: candidate' in output
    assert 'generation 3/3' in output
    result = json.loads((bag / 'result.json').read_text())
    assert list(result['objectives']) == ['position_1', 'orientation_1']
    assert result['evaluations'] == 3 * 6 and result['stop_reason'] == 'maxiter=3'
    table = read_run(bag, run_id=result['run_id']).generation_summaries
    final = table.row(len(table) - 1)
    assert final['final'] and result['best_candidate_id'] == final['best_candidate_id']
    assert result['fitness'] == final['best_fitness']
    assert list(result['objectives'].values()) == list(final['best_objectives'])


def test_same_summaries_with_one_and_three_evaluators(one_evaluator_run, tmp_path):
    bag, _ = one_evaluator_run
    three = tmp_path / 'three'
    run(three, 3)
    assert summaries(bag) == summaries(three)
    evaluators = set(read_run(three).evaluations['evaluator_id'])
    assert len(evaluators) >= 2, 'the work was not shared among the evaluators'


def test_bag_holds_every_published_message(one_evaluator_run):
    bag, _ = one_evaluator_run
    record = read_run(bag)
    published = json.loads((bag / 'result.json').read_text())['published']
    assert record.message_counts['/candidates'] == published['candidates']
    assert record.message_counts['/generation_summary'] == published['generation_summary']
    assert record.message_counts['/run_info'] == published['run_info'] == 1
    # the optimizer starts once the recorder records (ros.runner): from the first candidate on
    first_sends = record.candidates['candidate_id'][record.candidates['attempt'] == 0]
    assert sorted(first_sends) == list(range(3 * 6))
    # each evaluator counts its answers in its heartbeats (EvaluatorStatus.evaluations_done)
    statuses = record.evaluator_status
    last_count = {}
    for evaluator, done in zip(statuses['evaluator_id'], statuses['evaluations_done']):
        last_count[evaluator] = max(int(done), last_count.get(evaluator, 0))
    answered = sum(last_count.values())
    assert record.message_counts['/evaluations'] == answered == 3 * 6


def test_bag_reads_back_with_independent_readers(one_evaluator_run):
    bag, _ = one_evaluator_run
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    mcap_file = next(bag.glob('*.mcap'))
    with open(mcap_file, 'rb') as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        decoded = sum(1 for _ in reader.iter_decoded_messages())
    assert decoded == sum(read_run(bag).message_counts.values())
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import get_typestore, Stores
    with AnyReader([bag], default_typestore=get_typestore(Stores.ROS2_JAZZY)) as reader:
        count = sum(1 for connection, _, raw in reader.messages()
                    if reader.deserialize(raw, connection.msgtype) is not None)
    assert count == decoded


def evaluator_processes(runner):
    return [child for child in psutil.Process(runner.pid).children(recursive=True)
            if 'evaluator_node' in ' '.join(child.cmdline())]


def run_killing_an_evaluator(bag, budget, extra=(), after='generation 1/'):
    """Run with 2 evaluators, SIGKILL one once a line holds `after`; return the output."""
    process = start_run(bag, 2, extra=extra, budget=budget)
    lines = []
    reader = threading.Thread(target=lambda: lines.extend(process.stdout), daemon=True)
    reader.start()
    deadline = time.monotonic() + 120
    while not any(after in line for line in lines):
        assert time.monotonic() < deadline and process.poll() is None, ''.join(lines)
        time.sleep(0.05)
    victims = evaluator_processes(process)
    assert len(victims) == 2
    victims[0].send_signal(signal.SIGKILL)
    process.wait(timeout=240)
    reader.join(timeout=10)
    assert process.returncode == 0, ''.join(lines)
    return ''.join(lines)


def test_killed_evaluator_does_not_change_the_result(one_evaluator_run, tmp_path):
    bag, _ = one_evaluator_run
    killed = tmp_path / 'killed'
    run_killing_an_evaluator(killed, BUDGET, after='generation 1/3')
    record = read_run(killed)
    told = record.generation_summaries['evaluations'][-1]
    assert told == 3 * 6
    ok = record.evaluations.select(record.evaluations['status'] == 0)
    assert sorted(set(ok['candidate_id'])) == list(range(18))
    assert max(record.candidates['attempt']) >= 1, 'no candidate had to be sent again'
    assert summaries(killed) == summaries(bag)


def run_processes(runner):
    return [child for child in psutil.Process(runner.pid).children(recursive=True)
            if 'hand_codesign' in ' '.join(child.cmdline())]


def secrets_of(runner, deadline):
    """Return the run secret and evaluator keys as the same user can read them (environ)."""
    found = set()
    while len(found) < 3:
        assert runner.poll() is None, runner.stdout.read()
        assert time.monotonic() < deadline, 'no keys found in the environments of the run'
        for child in run_processes(runner):
            with contextlib.suppress(psutil.Error):
                environment = child.environ()
                if 'HAND_CODESIGN_RUN_SECRET' in environment:
                    found.add(environment['HAND_CODESIGN_RUN_SECRET'])
                if 'HAND_CODESIGN_EVALUATOR_KEY' in environment:
                    found.add(json.loads(environment['HAND_CODESIGN_EVALUATOR_KEY'])['key'])
        time.sleep(0.05)
    return found


def test_a_forger_without_a_key_changes_nothing_and_is_counted(one_evaluator_run, tmp_path):
    bag, _ = one_evaluator_run
    disturbed = tmp_path / 'disturbed'
    key_file = tmp_path / 'host-b.key'
    for _ in range(5):   # another run of this host may claim the free domain first
        domain = free_domain()
        env = dict(os.environ, ROS_DOMAIN_ID=str(domain),
                   FASTRTPS_DEFAULT_PROFILES_FILE=str(ANNOUNCE_OFTEN))
        # the intruder waits for the run's RunInfo, then forges an answer to every candidate
        intruder = subprocess.Popen([sys.executable, str(HERE / 'intruder.py')],
                                    env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                    text=True)
        runner = start_run(disturbed, 2, domain=domain,
                           extra=['--write-key-file', f'host-b={key_file}'])
        with contextlib.suppress(subprocess.TimeoutExpired):
            runner.wait(timeout=3)
        if runner.poll() is None:
            break
        intruder.kill()
        intruder.communicate()
        assert 'in use by another run' in runner.stdout.read()
    keys = secrets_of(runner, time.monotonic() + 60)
    command_lines = set()
    for process in psutil.process_iter():
        with contextlib.suppress(psutil.Error):  # a process may end (or be a zombie) meanwhile
            if process.pid != os.getpid():
                command_lines.add(' '.join(process.cmdline()))
    output = finish(runner)
    forgeries, errors = intruder.communicate(timeout=120)
    assert intruder.returncode == 0, errors
    forged = int(forgeries.split()[1])
    assert forged >= 18, forgeries
    assert summaries(disturbed) == summaries(bag)
    result = json.loads((disturbed / 'result.json').read_text())
    trust = result['trust']
    assert 0 < trust['rejected_evaluations'] <= forged
    record = read_run(disturbed, run_id=result['run_id'])
    assert 'foreign-run' in record.run_ids
    # the forged summaries are in the bag, left out by every reader, and counted
    assert record.rejected_summaries == FORGED_SUMMARIES
    # its heartbeats (a phantom evaluator's, and evaluator-0's asking for 100 candidates) are
    # in the bag too, but the optimizer heard neither: nothing went to the phantom
    assert 'phantom' in set(record.evaluator_status['evaluator_id'])
    assert 'phantom' not in set(record.candidates['evaluator_id'])
    ignored = trust_counts(record)['rejected_by_evaluators']
    assert ignored >= 2 * 3 + 2, 'the unsigned candidates and RunInfo were not all ignored'
    answered = set(record.evaluations['candidate_id'].tolist())
    assert not answered & {10**9, 10**9 + 1, 10**9 + 2}, 'an unsigned candidate was answered'
    # the run secret and the evaluators' keys: in no command line, file of the bag, or output
    assert len(keys) == 3
    contents = [path.read_bytes() for path in disturbed.rglob('*') if path.is_file()]
    contents += [output.encode(), errors.encode()]
    for key in keys:
        assert not any(key in line for line in command_lines)
        assert not any(key.encode() in data or bytes.fromhex(key) in data for data in contents)
    assert key_file.stat().st_mode & 0o777 == 0o600
    assert json.loads(key_file.read_text())['evaluator_id'] == 'host-b'
    assert not any(key in key_file.read_text() for key in keys)
    report = subprocess.run([sys.executable, '-m', 'hand_codesign.cli', 'analyze',
                             str(disturbed), '--out', str(tmp_path / 'report')],
                            capture_output=True, text=True, cwd=ROOT)
    assert (f'{trust["rejected_evaluations"]} evaluation(s) ignored by the optimizer'
            in report.stdout), report.stdout + report.stderr
    assert f'{ignored} RunInfo/Candidate message(s) ignored' in report.stdout
    assert (f'{FORGED_SUMMARIES} GenerationSummary message(s) in the bag failed their '
            'signature check') in report.stdout
    # the forgeries are in the bag, but the analysis takes what the optimizer told
    assert 'untold (answers the summaries contradict)' in report.stdout
    assert f'fitness {result["fitness"]:.4g}' in report.stdout.split('best design:')[1]


def test_an_evaluator_with_its_key_that_lies_is_caught(one_evaluator_run, tmp_path):
    bag, _ = one_evaluator_run
    secret = new_secret()
    keys = RunKeys(secret)
    key_file = tmp_path / 'liar.key'
    key_file.write_text(keys.credential('liar').text())
    key_file.chmod(0o600)
    with claimed_domain(None) as domain_id:
        env = dict(os.environ, ROS_DOMAIN_ID=str(domain_id))
        lied = tmp_path / 'lied'
        processes = []

        def start(module, parameters, key=None, **popen):
            command = [sys.executable, *module, '--ros-args']
            for name, value in parameters.items():
                command += ['-p', f'{name}:={value}']
            processes.append(subprocess.Popen(command, cwd=ROOT, env=dict(env, **(key or {})),
                                              **popen))
            return processes[-1]

        try:
            recorder = start(['-m', 'hand_codesign.ros.recorder_node'], {'bag_path': lied},
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
            for line in recorder.stdout:
                if 'recorder ready' in line:
                    break
            threading.Thread(target=recorder.stdout.read, daemon=True).start()
            for index in range(2):
                credential = keys.credential(f'evaluator-{index}').text()
                start(['-m', 'hand_codesign.ros.evaluator_node'],
                      {'evaluator_id': f'evaluator-{index}', 'subscribers_expected': 2},
                      {'HAND_CODESIGN_EVALUATOR_KEY': credential}, stdout=subprocess.DEVNULL)
            start([str(HERE / 'liar.py')],
                  {'key_file': key_file, 'subscribers_expected': 2, 'capacity': 3},
                  stdout=subprocess.DEVNULL)
            optimizer = start(
                ['-m', 'hand_codesign.commands.optimizer'],
                {'task_file': TASK, 'seed': 7, 'iterations': 3, 'population': 6,
                 'world_states': 3, 'evaluators_expected': 3, 'subscribers_expected': 1,
                 'result_file': lied / 'result.json'},
                {'HAND_CODESIGN_RUN_SECRET': secret.hex()}, stderr=subprocess.PIPE, text=True)
            _, log = optimizer.communicate(timeout=180)
            assert optimizer.returncode == 0, log
        finally:
            for process in reversed(processes):
                if process.poll() is None:
                    process.send_signal(signal.SIGINT)
                process.wait(timeout=60)
    assert summaries(lied) == summaries(bag)
    result = json.loads((lied / 'result.json').read_text())
    assert result['trust']['quarantined'] == ['liar'], log
    assert 'liar returned objectives that others contradict' in log
    record = read_run(lied)
    liar_rows = record.evaluations.select(record.evaluations['evaluator_id'] == 'liar')
    assert len(liar_rows) >= 1
    assert summaries(lied)[0]['evaluations'] == 6
    counts = trust_counts(record)
    assert counts['quarantined'] == ['liar'] and counts['audit_evaluations'] >= 2


def test_hierarchy_task_searches_structures_bottom_up(tmp_path):
    bag = tmp_path / 'hierarchy'
    output = finish(start_run(bag, 2, budget=[
        '--iterations', '1', '--population', '4', '--world-states', '2', '--seed', '3'],
        task=ROOT / 'config' / 'tasks' / 'task4.yaml'))
    summaries_table = read_run(bag).generation_summaries
    checks = summaries_table.select(summaries_table['check'])
    structures = [tuple(structure) for structure in checks['structure']]
    assert structures[:3] == [(1,), (2,), (1, 1)]
    assert 'structure [1] (optimized with seeds ' in output
    assert 'best design on the held-out worlds' in output
    result = json.loads((bag / 'result.json').read_text())
    assert tuple(result['structure']) in structures


def test_terminated_run_stops_every_process_and_closes_its_bag(tmp_path):
    bag = tmp_path / 'terminated'
    process = start_run(bag, 2, budget=['--iterations', '50', '--population', '6',
                                        '--world-states', '3'])
    lines = []
    threading.Thread(target=lambda: lines.extend(process.stdout), daemon=True).start()
    deadline = time.monotonic() + 120
    while not any('generation 2/50' in line for line in lines):
        assert time.monotonic() < deadline and process.poll() is None, ''.join(lines)
        time.sleep(0.05)
    children = psutil.Process(process.pid).children(recursive=True)
    assert len(children) >= 4
    process.send_signal(signal.SIGTERM)
    assert process.wait(timeout=120) == 130
    gone, alive = psutil.wait_procs(children, timeout=10)
    assert not alive, [child.cmdline() for child in alive]
    record = read_run(bag)
    assert not record.truncated and not record.warnings
    assert len(record.generation_summaries) >= 2


def test_nodes_started_by_hand_with_parameter_files(tmp_path):
    with claimed_domain(None) as domain_id:    # held: no run of this host joins the domain
        nodes_by_hand(tmp_path, dict(os.environ, ROS_DOMAIN_ID=str(domain_id)))


def node_names(env, expected):
    """Return the node names the domain of env holds (`ros2 node list`), once `expected` are."""
    probe = ('import rclpy, time; rclpy.init(); node = rclpy.create_node("probe"); '
             'end = time.monotonic() + 30\n'
             f'while len(node.get_node_names()) < {expected} and time.monotonic() < end: '
             'time.sleep(0.1)\n'
             'print(" ".join(node.get_node_names()))')
    return subprocess.run([sys.executable, '-c', probe], env=env, capture_output=True,
                          text=True, check=True, timeout=60).stdout.split()


def nodes_by_hand(tmp_path, env):
    # started from a folder outside the repository, as `ros2 run` from a user's home: the
    # optimizer's file names its task relative to the package (found in its share/)
    bin_folder = pathlib.Path(sys.prefix) / 'bin'
    config = ROOT / 'config'

    def node(name, *parameters, remaps=(), **popen):
        command = [str(bin_folder / name), '--ros-args', '--params-file',
                   str(config / f'{name}.yaml')]
        for parameter in parameters:
            command += ['-p', parameter]
        for remap in remaps:
            command += ['-r', remap]
        return subprocess.Popen(command, cwd=tmp_path, env=env, **popen)

    bag = tmp_path / 'by-hand'
    recorder = node('recorder', f'bag_path:={bag}')
    # two evaluators started alike (one given an id), each named after its id
    evaluators = [node('evaluator', 'subscribers_expected:=2', stdout=subprocess.DEVNULL),
                  node('evaluator', 'subscribers_expected:=2', 'evaluator_id:=lab-hand-2',
                       stdout=subprocess.DEVNULL)]
    # renamed: the `/**:` parameter file still gives it its task file
    optimizer = node('optimizer', 'iterations:=2', 'population:=4', 'world_states:=2',
                     'evaluators_expected:=2', f'result_file:={tmp_path / "result.json"}',
                     remaps=['__node:=my_optimizer'], stderr=subprocess.PIPE, text=True)
    try:
        _, log = optimizer.communicate(timeout=180)
        assert optimizer.returncode == 0, log
        names = node_names(env, expected=4)   # the probe, the recorder, the evaluators
    finally:
        for process in (optimizer, *evaluators, recorder):
            if process.poll() is None:
                process.send_signal(signal.SIGINT)
            process.wait(timeout=60)
    evaluator_names = {name for name in names if name not in ('probe', 'recorder')}
    assert 'lab_hand_2' in evaluator_names and len(evaluator_names) == 2, names
    assert f'{socket.gethostname()}_{evaluators[0].pid}'.replace('-', '_') in {
        name.removeprefix('evaluator_') for name in evaluator_names}, names
    result = json.loads((tmp_path / 'result.json').read_text())
    assert result['task'] == 'task5' and result['evaluations'] == 8
    summaries_table = read_run(bag).generation_summaries
    assert list(summaries_table['final']) == [False, False, True]


def test_evaluator_keeps_its_heartbeat_while_it_evaluates(tmp_path):
    # candidates of 500 worlds take seconds; the heartbeat period is 0.5 s
    bag = tmp_path / 'long'
    finish(start_run(bag, 1, budget=['--iterations', '1', '--population', '3',
                                     '--world-states', '500', '--seed', '7']))
    record = read_run(bag)
    assert np.max(record.evaluations['wall_time']) > 1.5
    stamps = np.sort(record.evaluator_status['stamp']) * 1e-9
    assert np.max(np.diff(stamps)) < 1.0


# what `ros2 topic echo /generation_summary` in the user's shell does: wait for a summary
LISTENER = """
from hand_codesign.ros import topics
import rclpy
import time
rclpy.init()
node = rclpy.create_node('shell_listener')
heard = []
name = topics.GENERATION_SUMMARY
node.create_subscription(topics.MESSAGE_TYPES[name], name, heard.append, topics.QOS[name])
print('ready', flush=True)
end = time.monotonic() + 120
while not heard and time.monotonic() < end:
    rclpy.spin_once(node, timeout_sec=0.1)
print(len(heard))
"""


def test_run_joins_the_ros_domain_of_the_users_shell(tmp_path):
    for attempt in range(5):   # another run of this host may claim the free domain first
        domain = free_domain()
        env = dict(os.environ, ROS_DOMAIN_ID=str(domain))
        # the listener starts before the run, so the run finds it when it announces itself
        # again (test/ros/announce_long.xml): a run of the tests can end before Fast DDS's 3 s
        listener_env = dict(env, FASTRTPS_DEFAULT_PROFILES_FILE=str(ANNOUNCE_OFTEN))
        listener = subprocess.Popen([sys.executable, '-c', LISTENER], env=listener_env,
                                    stdout=subprocess.PIPE, text=True)
        listener.stdout.readline()   # subscribed before the run starts: no summary is missed
        command = [sys.executable, '-m', 'hand_codesign.cli', 'run', '--task', str(TASK),
                   '--evaluators', '1', '--bag', str(tmp_path / str(attempt)), *BUDGET]
        run = subprocess.run(command, cwd=ROOT, env=env, capture_output=True, text=True,
                             timeout=300)
        heard, _ = listener.communicate(timeout=150)
        if 'in use by another run' not in run.stderr:
            break
    assert run.returncode == 0, run.stdout + run.stderr
    assert f"ROS_DOMAIN_ID={domain} (the environment's ROS_DOMAIN_ID)" in run.stdout
    assert int(heard) >= 1, run.stdout + run.stderr


def test_a_quiet_run_whose_optimizer_fails_still_says_why_and_logs_it(tmp_path, capsys):
    bag = tmp_path / 'failed'
    with claimed_domain(None) as domain:
        system = System(bag, domain, quiet=True)
        try:
            code = system.run(0, 'hand_codesign.commands.optimizer',
                              {'task_file': str(TASK), 'population': -3})
        finally:
            system.stop_all()
    reason = 'Parameter population out of range'
    assert code == 2
    assert reason in capsys.readouterr().err
    assert reason in (bag / 'logs' / 'optimizer.log').read_text()
    assert all(process.poll() is not None for process in (system.optimizer, system.recorder))
