"""
Runs whose processes die or whose hosts lose their link, compared with a clean run.

Each run has the budget of the session's clean run (analysis_run.real_run, Task 5). What a user
checks: the run finishes, prints what happened, and its generation summaries are those of the
clean run; the bag of a run whose recorder was killed is closed, readable by rosbags, and holds
every message of the run once.

The test hosts are the project's own (Hosts): two network namespaces on two subnets behind a
router namespace that carries no multicast, each with its own /dev/shm, created by the test
as root and deleted afterwards with whatever still runs in them; nothing leaves them. Where
namespaces are not permitted the test is skipped and says why.
"""

import collections
import contextlib
import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import time

from analysis_run import BUDGET
from analysis_run import TASK
from hand_codesign.bag.reader import read_run
import psutil
import pytest
from rosbags.rosbag2 import Reader
from test_system import free_domain
from test_system import ROOT
from test_system import start_run
from test_system import summaries
import yaml

pytestmark = pytest.mark.system


@pytest.fixture
def clean_run(real_run):
    """Return the bag of the session's clean run (analysis_run.real_run, same budget)."""
    return real_run.bag


class Watched:
    """A run started in the background whose output lines are collected as they come."""

    def __init__(self, bag, evaluators, extra=(), host=None):
        if host is None:
            self.process = start_run(bag, evaluators, budget=BUDGET, extra=extra)
        else:   # `hand-codesign run` on a test host
            self.process = subprocess.Popen(
                host + [sys.executable, '-m', 'hand_codesign.cli', 'run', '--task', str(TASK),
                        '--evaluators', str(evaluators), '--bag', str(bag),
                        '--domain-id', 'auto', *BUDGET, *extra],
                cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        self.lines = []
        self.reader = threading.Thread(target=lambda: self.lines.extend(self.process.stdout),
                                       daemon=True)
        self.reader.start()

    def output(self):
        return ''.join(self.lines)

    def wait_for(self, condition, timeout=120):
        deadline = time.monotonic() + timeout
        while True:
            found = condition()
            if found:
                return found
            assert time.monotonic() < deadline and self.process.poll() is None, self.output()
            time.sleep(0.02)

    def child(self, text):
        """Return the run's child process whose command line contains text, or None."""
        for process in psutil.Process(self.process.pid).children(recursive=True):
            try:
                if text in ' '.join(process.cmdline()):
                    return process
            except psutil.NoSuchProcess:
                pass
        return None

    def finish(self, timeout=300):
        try:
            self.process.wait(timeout=timeout)
        except subprocess.TimeoutExpired:  # what the run said is what tells why it hung
            self.process.kill()
            self.process.wait()
            self.reader.join(timeout=10)
            raise AssertionError(f'the run did not end in {timeout} s:\n{self.output()}')
        self.reader.join(timeout=10)
        assert self.process.returncode == 0, self.output()
        return self.output()


def node_name_in_log(log):
    """Return the node name an evaluator's log shows in its first line, '[LEVEL] [name]: ...'."""
    return log.read_text().split('] [', 1)[1].split(']', 1)[0]


def test_evaluator_killed_during_start_up(clean_run, tmp_path):
    bag = tmp_path / 'start-up'
    run = Watched(bag, 2)
    victim = run.wait_for(lambda: run.child('evaluator_id:=evaluator-1 '))
    victim.send_signal(signal.SIGKILL)   # the run is still waiting for its evaluators
    output = run.finish()
    assert 'evaluator-1 exited (code -9); restarting it' in output
    assert 'evaluators ready, starting' in output
    assert summaries(bag) == summaries(clean_run)
    # every evaluator of the run has a node name of its own, the restarted one too (the run is
    # too short for a graph observer to see each node reliably; each node's log names it)
    logs = bag / 'logs'
    assert node_name_in_log(logs / 'evaluator-0.log') == 'evaluator_0'
    assert node_name_in_log(logs / 'evaluator-1-r1.log') == 'evaluator_1_r1'


def test_recorder_killed_mid_run(clean_run, tmp_path):
    bag = tmp_path / 'recorder'
    run = Watched(bag, 2)
    run.wait_for(lambda: 'generation 1/4' in run.output())
    run.child('recorder_node').send_signal(signal.SIGKILL)
    output = run.finish()
    assert 'recorder exited (code -9); restarting it' in output
    assert summaries(bag) == summaries(clean_run)
    information = yaml.safe_load((bag / 'metadata.yaml').read_text())[
        'rosbag2_bagfile_information']
    assert information['relative_file_paths'] == ['recorder_0.mcap', 'recorder_1.mcap']
    with Reader(bag) as reader:     # rosbags takes it: every file closed and indexed
        assert sum(1 for _ in reader.messages()) == information['message_count']
    record = read_run(bag)
    assert not record.truncated
    published = json.loads((bag / 'result.json').read_text())['published']
    assert record.message_counts['/candidates'] == published['candidates']
    assert record.message_counts['/generation_summary'] == published['generation_summary']
    assert record.message_counts['/run_info'] == 1
    sent = list(zip(record.candidates['candidate_id'], record.candidates['attempt']))
    assert len(sent) == len(set(sent))
    answers = list(zip(record.evaluations['candidate_id'], record.evaluations['attempt'],
                       record.evaluations['evaluator_id']))
    assert len(answers) == len(set(answers))
    ok = record.evaluations.select(record.evaluations['status'] == 0)
    assert sorted(set(ok['candidate_id'])) == list(range(24))
    # each evaluator counts its answers in its heartbeats (EvaluatorStatus.evaluations_done,
    # sent right after every answer); its last count is what it published
    last_count = {}
    statuses = record.evaluator_status
    for evaluator, done in zip(statuses['evaluator_id'], statuses['evaluations_done']):
        last_count[evaluator] = max(int(done), last_count.get(evaluator, 0))
    assert record.message_counts['/evaluations'] == sum(last_count.values())


class Hosts:
    """
    Two hosts of the test's own on a network without multicast.

    Host A (10.213.1.1) and host B (10.213.2.1) are network namespaces on two subnets joined
    by a router namespace through veth pairs. The router forwards unicast only: Linux routes
    no multicast without a multicast routing daemon, so ROS 2's default discovery cannot
    cross it (`multicast_reaches_b` checks that). Each host has its own /dev/shm, as separate
    machines do; otherwise Fast DDS would find and talk to the other host's processes through
    shared memory.
    """

    def __init__(self, folder):
        tag = os.getpid() % 100000
        self.a, self.b, self.router = f'hc{tag}a', f'hc{tag}b', f'hc{tag}r'
        self.link_b = f'hc{tag}vb'
        self.address_a, self.address_b = '10.213.1.1', '10.213.2.1'
        self.shm = {self.a: folder / 'shm-a', self.b: folder / 'shm-b'}
        self.created = []

    def create(self):
        """Create hosts and router; return None, or why they cannot be created here."""
        tag = self.link_b[:-2]
        commands = []
        for host in (self.a, self.b, self.router):
            commands += [['netns', 'add', host], ['-n', host, 'link', 'set', 'lo', 'up']]
        for host, link, address in ((self.a, f'{tag}va', self.address_a),
                                    (self.b, self.link_b, self.address_b)):
            router_link, router_address = f'{link}r', address.rsplit('.', 1)[0] + '.254'
            commands += [
                ['link', 'add', link, 'type', 'veth', 'peer', 'name', router_link],
                ['link', 'set', link, 'netns', host],
                ['link', 'set', router_link, 'netns', self.router],
                ['-n', host, 'addr', 'add', f'{address}/24', 'dev', link],
                ['-n', self.router, 'addr', 'add', f'{router_address}/24', 'dev', router_link],
                ['-n', host, 'link', 'set', link, 'up'],
                ['-n', self.router, 'link', 'set', router_link, 'up'],
                ['-n', host, 'route', 'add', 'default', 'via', router_address]]
        for command in commands:
            done = subprocess.run(['ip', *command], capture_output=True, text=True)
            if command[:2] == ['netns', 'add'] and done.returncode == 0:
                self.created.append(command[2])
            if done.returncode != 0:
                return f'`ip {" ".join(command)}` failed: {done.stderr.strip()}'
        forward = self.on(self.router, shm=False) + [
            'sysctl', '-qw', 'net.ipv4.ip_forward=1']
        done = subprocess.run(forward, capture_output=True, text=True)
        if done.returncode != 0:
            return f'cannot make the router forward: {done.stderr.strip()}'
        for folder in self.shm.values():
            folder.mkdir()
        return None

    def on(self, host, shm=True):
        """Return the command prefix that runs a command on a host, with its own /dev/shm."""
        prefix = ['ip', 'netns', 'exec', host]
        if not shm:
            return prefix
        return prefix + ['unshare', '--mount', '--propagation', 'private', 'sh', '-c',
                         f'mount --bind {self.shm[host]} /dev/shm && exec "$0" "$@"']

    def multicast_reaches_b(self):
        """Return whether a multicast datagram sent on host A arrives on host B."""
        receive = (
            'import socket, struct\n'
            's = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)\n'
            's.bind(("", 7400))\n'
            's.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, struct.pack('
            '"4s4s", socket.inet_aton("239.255.0.1"), socket.inet_aton("0.0.0.0")))\n'
            'print("ready", flush=True)\n'
            's.settimeout(1.5)\n'
            'try:\n    s.recv(64)\n    print("received")\n'
            'except socket.timeout:\n    print("nothing")\n')
        send = (
            'import socket, time\n'
            's = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)\n'
            's.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 32)\n'
            'for _ in range(5):\n'
            '    s.sendto(b"hello", ("239.255.0.1", 7400))\n    time.sleep(0.1)\n')
        receiver = subprocess.Popen(self.on(self.b, shm=False) + [sys.executable, '-c', receive],
                                    stdout=subprocess.PIPE, text=True)
        assert receiver.stdout.readline().strip() == 'ready'
        subprocess.run(self.on(self.a, shm=False) + [sys.executable, '-c', send], check=True)
        return receiver.communicate(timeout=30)[0].strip() == 'received'

    def cut_b(self):
        subprocess.run(['ip', '-n', self.b, 'link', 'set', self.link_b, 'down'], check=True)

    def destroy(self):
        """Kill what still runs on the hosts and delete them (their veth pairs go with them)."""
        for host in self.created:
            pids = subprocess.run(['ip', 'netns', 'pids', host], capture_output=True,
                                  text=True).stdout.split()
            for pid in pids:
                with contextlib.suppress(ProcessLookupError):
                    os.kill(int(pid), signal.SIGKILL)
            subprocess.run(['ip', 'netns', 'del', host], capture_output=True)


@pytest.fixture
def hosts(tmp_path):
    if shutil.which('ip') is None or shutil.which('unshare') is None:
        pytest.skip('test hosts need `ip` (iproute2) and `unshare` (util-linux)')
    if os.geteuid() != 0:
        pytest.skip('test hosts need root to create network namespaces')
    test_hosts = Hosts(tmp_path)
    try:
        problem = test_hosts.create()
        if problem:
            pytest.skip(f'network namespaces are not permitted here: {problem}')
        yield test_hosts
    finally:
        test_hosts.destroy()


def evaluator_on(hosts, host, key_file, server, domain, log):
    """Start an evaluator on a test host that finds the run through the discovery server."""
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain), ROS_DISCOVERY_SERVER=server,
               ROS_AUTOMATIC_DISCOVERY_RANGE='SUBNET')
    return subprocess.Popen(
        hosts.on(host) + [sys.executable, '-m', 'hand_codesign.ros.evaluator_node',
                          '--ros-args', '-p', f'key_file:={key_file}',
                          '-p', 'subscribers_expected:=2'],
        env=env, stdout=log, stderr=subprocess.STDOUT)


def written(path):
    return path.exists() and path.stat().st_size > 0


def test_host_b_joins_through_the_discovery_server_then_its_link_is_cut(
        clean_run, hosts, tmp_path):
    bag, domain, port = tmp_path / 'hosts', free_domain(), 11811
    assert not hosts.multicast_reaches_b(), 'the test network carries multicast'
    started = []
    # each host's evaluator holds the key the run writes for it (outside the bag folder)
    key_a, key_b = tmp_path / 'host-a.key', tmp_path / 'host-b.key'
    try:
        # host A: the run with no evaluator of its own
        run = Watched(bag, 0, host=hosts.on(hosts.a),
                      extra=['--discovery-server', str(port), '--domain-id', str(domain),
                             '--write-key-file', f'host-a={key_a}',
                             '--write-key-file', f'host-b={key_b}'])
        run.wait_for(lambda: written(key_b))
        with open(tmp_path / 'host-b.log', 'w') as log:
            started.append(evaluator_on(hosts, hosts.b, key_b, f'{hosts.address_a}:{port}',
                                        domain, log))
        run.wait_for(lambda: 'generation 1/4' in run.output())
        with open(tmp_path / 'host-a.log', 'w') as log:
            started.append(evaluator_on(hosts, hosts.a, key_a, f'127.0.0.1:{port}',
                                        domain, log))
        hosts.cut_b()
        output = run.finish()
    finally:
        for process in started:
            process.kill()
            process.wait()
    assert f'ROS_DISCOVERY_SERVER={hosts.address_a}:{port}' in output
    assert summaries(bag) == summaries(clean_run)
    record = read_run(bag)
    ok = record.evaluations.select(record.evaluations['status'] == 0)
    by_host = collections.Counter(ok['evaluator_id'])
    assert by_host['host-b'] >= 6 and by_host['host-a'] >= 1, by_host
    assert max(record.candidates['attempt']) >= 1, 'nothing of host B had to be sent again'


def test_run_without_its_evaluators_says_so_and_stops_cleanly(tmp_path):
    bag = tmp_path / 'alone'
    run = start_run(bag, 0, budget=BUDGET, extra=['--start-timeout', '1'])
    output, _ = run.communicate(timeout=120)
    assert run.returncode == 1, output
    assert 'the evaluators did not join within 1 s (--start-timeout)' in output
    assert f'bag: {bag}' in output
    record = read_run(bag)
    assert not record.truncated and record.message_counts['/run_info'] == 1
    assert (bag / 'metadata.yaml').exists()
