"""
Load test: many evaluator processes join one run through the discovery server.

Runs `hand-codesign run --evaluators N --discovery-server PORT` (default 32 evaluators, Task 5,
a small budget) and samples the CPU time of every process of the run while it goes. Then it
checks that every count matches (candidates sent = published, every candidate answered, the
evaluations in the bag = those the evaluators say they published, each candidate told once)
and prints:

- the optimizer's own CPU time per candidate while the run is going (from "evaluators ready"
  to its end: dispatch, heartbeats of N evaluators, messages, CMA-ES), its start-up apart;
- the reference measured in the same run: the evaluators' CPU time per evaluation over the
  same span (their heartbeats included);
- their ratio: how many evaluators, each busy all the time with evaluations of this cost, one
  optimizer core could feed. An evaluation of the paper's size costs far more than the small
  one here (more worlds, a longer rollout) while the optimizer's cost per candidate stays, so
  the ratio grows with it; scale it by the evaluation time of the task at hand;
- the discovery server's CPU time and the bag's bytes per candidate.

On a machine with fewer cores than evaluators the evaluators take turns; the per-candidate
figures are CPU times, not wall times, so they hold all the same.

Run: python bench/bench_scale.py [--evaluators 32] [--population 64] [--iterations 3]
"""

import argparse
import json
import pathlib
import subprocess
import sys
import tempfile
import threading
import time

from hand_codesign.bag.reader import read_run
from hand_codesign.ros.runner import claimed_domain
import psutil

ROOT = pathlib.Path(__file__).resolve().parents[1]
TASK = ROOT / 'config' / 'tasks' / 'task5.yaml'


def role_of(process):
    """Return 'optimizer', 'evaluator', 'recorder', 'server' or None for a run's process."""
    try:
        command = ' '.join(process.cmdline())
    except psutil.Error:
        return None
    for text, role in (('commands.optimizer', 'optimizer'), ('evaluator_node', 'evaluator'),
                       ('recorder_node', 'recorder'), ('fast-discovery-server', 'server')):
        if text in command:
            return role
    return None


class Sampler:
    """CPU times of the run's processes, sampled until they end (the last sample stands)."""

    def __init__(self, runner):
        self.runner = psutil.Process(runner.pid)
        self.cpu = {}      # pid -> (role, user + system seconds)
        self.at_start = {}  # pid -> seconds at the first sample after "evaluators ready"
        self.started = threading.Event()

    def sample(self):
        try:
            children = self.runner.children(recursive=True)
        except psutil.Error:
            return
        for child in children:
            role = role_of(child)
            if role is None:
                continue
            try:
                times = child.cpu_times()
            except psutil.Error:
                continue
            self.cpu[child.pid] = (role, times.user + times.system)
            if self.started.is_set():
                self.at_start.setdefault(child.pid, times.user + times.system)

    def total(self, role):
        """Return the CPU seconds of the processes of a role, start-up included."""
        return sum(seconds for kind, seconds in self.cpu.values() if kind == role)

    def running(self, role):
        """Return the CPU seconds of a role's processes after "evaluators ready"."""
        return sum(seconds - self.at_start.get(pid, seconds)
                   for pid, (kind, seconds) in self.cpu.items() if kind == role)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    parser.add_argument('--evaluators', type=int, default=32)
    parser.add_argument('--population', type=int, default=64)
    parser.add_argument('--iterations', type=int, default=3)
    parser.add_argument('--world-states', type=int, default=1)
    parser.add_argument('--port', type=int, default=0,
                        help="discovery server port (default: 11811 + the run's domain id)")
    arguments = parser.parse_args()
    with claimed_domain(None) as domain:   # a domain no run of this host holds now
        pass
    with tempfile.TemporaryDirectory() as folder:
        bag = pathlib.Path(folder) / 'scale'
        port = arguments.port or 11811 + domain
        command = [sys.executable, '-m', 'hand_codesign.cli', 'run', '--task', str(TASK),
                   '--evaluators', str(arguments.evaluators), '--bag', str(bag),
                   '--iterations', str(arguments.iterations), '--population',
                   str(arguments.population), '--world-states', str(arguments.world_states),
                   '--seed', '1', '--discovery-server', str(port), '--domain-id', str(domain)]
        started = time.monotonic()
        runner = subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE,
                                  stderr=subprocess.STDOUT, text=True)
        sampler = Sampler(runner)
        lines = []

        def read():
            for line in runner.stdout:
                lines.append(line)
                if 'evaluators ready' in line:
                    sampler.started.set()
        reader = threading.Thread(target=read, daemon=True)
        reader.start()
        while runner.poll() is None:
            sampler.sample()
            time.sleep(0.1)
        reader.join(timeout=10)
        wall = time.monotonic() - started
        if runner.returncode != 0:
            sys.exit('the run failed:\n' + ''.join(lines[-30:]))
        report(arguments, bag, sampler, wall)


def report(arguments, bag, sampler, wall):
    result = json.loads((bag / 'result.json').read_text())
    record = read_run(bag, run_id=result['run_id'])
    candidates = arguments.population * arguments.iterations
    published = result['published']
    ok = record.evaluations.select(record.evaluations['status'] == 0)
    answered = len(set(ok['candidate_id']))
    logged = sum(int(line.rsplit(' published ', 1)[1].split()[0])
                 for log in (bag / 'logs').glob('evaluator-*.log')
                 for line in log.read_text().splitlines() if ' published ' in line)
    evaluators_heard = len(set(record.evaluator_status['evaluator_id']))
    checks = {
        'candidates in the bag = published': record.message_counts['/candidates'] ==
        published['candidates'],
        'every candidate answered': answered == candidates,
        'evaluations in the bag = published by the evaluators':
            record.message_counts['/evaluations'] == logged,
        'evaluations told = candidates': result['evaluations'] == candidates,
        f'{arguments.evaluators} evaluators heard': evaluators_heard == arguments.evaluators,
        'evaluators that evaluated': len(set(ok['evaluator_id'])),
    }
    optimizer_total = sampler.total('optimizer')
    optimizer_run = sampler.running('optimizer')
    evaluations = int(record.message_counts['/evaluations'])
    per_evaluation = sampler.running('evaluator') / max(1, evaluations)
    size = sum(path.stat().st_size for path in bag.glob('*.mcap'))
    print(f'{arguments.evaluators} evaluators, {candidates} candidates '
          f'({arguments.iterations} x {arguments.population}, {arguments.world_states} worlds), '
          f'wall {wall:.1f} s')
    for name, value in checks.items():
        print(f'  check: {name}: {value}')
    print(f'optimizer CPU: {optimizer_total:.2f} s in all, {optimizer_run:.2f} s from '
          f'"evaluators ready" to its end = {1000 * optimizer_run / candidates:.2f} ms per '
          'candidate')
    print(f'reference, same run: evaluators CPU {sampler.total("evaluator"):.1f} s in all, '
          f'{sampler.running("evaluator"):.2f} s from "evaluators ready" to the end = '
          f'{1000 * per_evaluation:.2f} ms per evaluation ({evaluations} evaluations; '
          'heartbeats and idle waiting included)')
    ratio = per_evaluation / max(1e-9, optimizer_run / candidates)
    print(f'ratio evaluator CPU per evaluation / optimizer CPU per candidate: {ratio:.1f} '
          '(evaluators one optimizer core feeds at this evaluation cost)')
    heartbeats = record.message_counts['/evaluator_status']
    print(f'discovery server CPU: {sampler.total("server"):.2f} s; recorder CPU: '
          f'{sampler.total("recorder"):.2f} s')
    print(f'bag: {size} bytes = {size / candidates:.0f} bytes per candidate, '
          f'{heartbeats} heartbeats = {heartbeats / wall:.0f} per second of the run')


if __name__ == '__main__':
    main()
