"""
Time Table I's budgets on this machine: one Task 4 structure, Task 5 on MuJoCo; racing's saving.

Each timing is one real run (`hand-codesign run`, 2 evaluators unless --evaluators says
otherwise), so run it on an idle machine: it prints the processor, the load average before
and after, and the CPU seconds of each role of the run (evaluators, optimizer, recorder), so a
busy machine shows as evaluators getting less than the wall time of two cores.

  task4-structure   one Task 4 structure (config/tasks/task4.yaml without its hierarchy, the
                    structure --structure, default 2 3: the hierarchy's costliest two-finger
                    hand) at Table I's per-structure budget: MO-CMA-ES, 200 x 150 on 64
                    worlds (384 M steps at most). Target: <= 30 minutes.
  task5-mujoco      Table I Task 5 (config/tasks/task5.yaml) on MuJoCo: CMA-ES, 100 x 80 on 64
                    worlds, seed 101. Target: <= 12 minutes.
  racing BAG ...    per run (bag): generations, rollouts run and saved by racing (from the
                    summaries' told_worlds), physics steps simulated, wall seconds; a run
                    without racing saves none. For raced against unraced runs of a
                    `hand-codesign reproduce` campaign.

--generations G runs only the first G generations and projects the whole budget from the
time per generation after the first (which also holds the start of the processes): a sample
of a few minutes, and a low one: early generations start more designs in collision, which
are not simulated. Without it the whole budget runs (10 to 30 minutes on 2 cores).

Usage: python bench/time_table1.py task4-structure [--structure 2 3] [--seed 1]
           [--generations G] [--engine pybullet] [--evaluators 2] [--keep DIR]
       python bench/time_table1.py task5-mujoco [--seed 101] [--generations G] [--keep DIR]
       python bench/time_table1.py racing BAG [BAG ...]
"""

import argparse
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import threading
import time

from hand_codesign.analysis.records import open_run, run_task_of
from hand_codesign.bag.reader import read_run
import numpy as np
import yaml

ROOT = pathlib.Path(__file__).resolve().parents[1]
TASKS = ROOT / 'config' / 'tasks'
TABLE_I = {'task4-structure': (200, 150, 64), 'task5-mujoco': (100, 80, 64)}
# the role of a run's process, by what its command line runs
ROLES = (('evaluator', 'evaluator_node'), ('optimizer', 'commands.optimizer'),
         ('recorder', 'recorder_node'))


def processor():
    """Return the processor's model name (/proc/cpuinfo) and the number of cores."""
    try:
        text = pathlib.Path('/proc/cpuinfo').read_text()
    except OSError:
        return f'unknown processor, {os.cpu_count()} cores'
    names = [line.split(':', 1)[1].strip() for line in text.splitlines()
             if line.startswith('model name')]
    return f'{names[0] if names else "unknown processor"}, {os.cpu_count()} cores'


def task4_structure(structure, folder):
    """Write Task 4 as one structure's search (its hierarchy left out) and return its path."""
    document = yaml.safe_load((TASKS / 'task4.yaml').read_text())
    document.pop('hierarchy', None)
    document['hand']['structure'] = [int(joints) for joints in structure]
    document['name'] = 'task4_' + '_'.join(str(joints) for joints in structure)
    path = folder / f'{document["name"]}.yaml'
    path.write_text(yaml.safe_dump(document, sort_keys=False))
    return path


class CpuWatch:
    """The CPU seconds of a process tree by role, sampled while it runs (/proc)."""

    def __init__(self, root_pid):
        self.root, self.seconds, self.done = root_pid, {}, threading.Event()
        self.thread = threading.Thread(target=self._watch, daemon=True)
        self.thread.start()

    def _watch(self):
        tick = os.sysconf('SC_CLK_TCK')
        while not self.done.wait(0.5):
            for pid in _descendants(self.root):
                try:
                    fields = pathlib.Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1]
                    command = pathlib.Path(f'/proc/{pid}/cmdline').read_text()
                except OSError:
                    continue
                role = next((role for role, module in ROLES if module in command), 'runner')
                values = fields.split()
                self.seconds[pid] = (role, (int(values[11]) + int(values[12])) / tick)

    def by_role(self):
        """Stop watching; return {role: CPU seconds}."""
        self.done.set()
        self.thread.join()
        totals = {}
        for role, seconds in self.seconds.values():
            totals[role] = totals.get(role, 0.0) + seconds
        return totals


def _descendants(root):
    parents = {}
    for entry in pathlib.Path('/proc').iterdir():
        if entry.name.isdigit():
            try:
                parents[int(entry.name)] = int(
                    (entry / 'stat').read_text().rsplit(')', 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
    found, grown = {root}, True
    while grown:
        grown = False
        for pid, parent in parents.items():
            if parent in found and pid not in found:
                found.add(pid)
                grown = True
    return found


def timed_run(task, arguments, engine, seed, bag):
    """Run the task at its Table I budget (or its first generations); return the figures."""
    iterations, population, worlds = TABLE_I[arguments.command]
    command = [sys.executable, '-m', 'hand_codesign.cli', 'run', '--task', str(task),
               '--evaluators', str(arguments.evaluators), '--bag', str(bag),
               '--seed', str(seed), '--iterations', str(arguments.generations or iterations),
               '--population', str(population), '--world-states', str(worlds),
               '--engine', engine, '--domain-id', 'auto', '--quiet']
    load = os.getloadavg()[0]
    started = time.perf_counter()
    process = subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True, start_new_session=True)
    watch = CpuWatch(process.pid)
    output, _ = process.communicate()
    wall = time.perf_counter() - started
    cpu = watch.by_role()
    if process.returncode != 0:
        raise SystemExit(f'{" ".join(command)} failed:\n{output}')
    return {'wall': wall, 'cpu': cpu, 'load_before': load, 'load_after': os.getloadavg()[0],
            'iterations': iterations, 'output': output.strip().splitlines()[-1:]}


def generation_times(bag):
    """Return the wall seconds (since the run started) at which each generation was told."""
    run_id = json.loads((bag / 'result.json').read_text())['run_id']
    table = read_run(bag, run_id=run_id).generation_summaries
    return [float(table['wall_time'][row]) for row in range(len(table))
            if not table['final'][row]]


def report(name, figures, bag, arguments):
    """Print a timing's figures, and the projection of a sampled one to the whole budget."""
    times = generation_times(bag)
    budget = figures['iterations']
    print(f'{name}: {processor()}; load average {figures["load_before"]:.2f} before, '
          f'{figures["load_after"]:.2f} after')
    print(f'  {len(times)} generations in {figures["wall"]:.0f} s wall ({times[-1]:.0f} s from '
          f'the first candidate to the last summary); CPU s by role: '
          + ', '.join(f'{role} {seconds:.0f}' for role, seconds in sorted(figures['cpu'].items())))
    if arguments.generations and len(times) > 1:
        per = (times[-1] - times[0]) / (len(times) - 1)
        projected = figures['wall'] - times[-1] + times[0] + per * (budget - 1)
        print(f"  projected to Table I's {budget} generations: {projected / 60:.1f} minutes "
              f'at least ({per:.1f} s per generation after the first)')
    else:
        print(f'  whole budget: {figures["wall"] / 60:.1f} minutes')
    rate = stepping(bag)
    print(f'  {rate[0] / 1e6:.1f} M physics steps, {rate[0] / max(times[-1], 1e-9):,.0f} a second')


def stepping(bag):
    """Return (physics steps, rollouts run) of every answer of a run (audits, rounds too)."""
    record = open_run(bag, warn=False)
    evaluations = record.evaluations
    ok = np.asarray(evaluations['status']) == 0
    task = run_task_of(record)
    steps = float(np.sum(np.asarray(evaluations['simulated_time'], dtype=float)[ok]))
    worlds = [len(row) // len(task.objective_names)
              for row, good in zip(evaluations['world_objectives'], ok) if good]
    return steps / task.time_step, int(np.sum(worlds))


def racing_report(bags):
    """Print per bag the rollouts racing saved, the steps and the wall time."""
    for bag in map(pathlib.Path, bags):
        record = open_run(bag, warn=False)
        table = record.generation_summaries
        task = run_task_of(record)
        told = saved = generations = 0
        for row in range(len(table)):
            if table['final'][row]:
                continue
            generations += 1
            ids = np.asarray(table['told_ids'][row]).ravel()
            told += len(ids) * task.num_world_states
            worlds = (np.asarray(table['told_worlds'][row]).ravel()
                      if 'told_worlds' in table else np.zeros(0))
            worlds = worlds[np.isfinite(worlds)] if worlds.dtype.kind == 'f' else worlds
            if len(worlds) == len(ids):
                saved += int(np.sum(task.num_world_states - worlds))
        steps, _ = stepping(bag)
        result = json.loads((bag / 'result.json').read_text())
        seconds = result.get('seconds') or max(generation_times(bag), default=0.0)
        print(f'{bag}: {generations} generations, racing '
              f'{"on" if task.worlds.racing is not None else "off"}; rollouts saved '
              f'{saved} of {told} ({saved / max(told, 1):.1%}); {steps / 1e6:.1f} M steps; '
              f'{seconds / 60:.1f} minutes')


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('command', choices=['task4-structure', 'task5-mujoco', 'racing'])
    parser.add_argument('bags', nargs='*', help='racing: the bags of the runs to compare')
    parser.add_argument('--structure', nargs='+', type=int, default=[2, 3])
    parser.add_argument('--seed', type=int)
    parser.add_argument('--generations', type=int, default=0)
    parser.add_argument('--engine', default='pybullet', choices=['pybullet', 'mujoco'])
    parser.add_argument('--evaluators', type=int, default=2)
    parser.add_argument('--keep', help="write the run's bag into this folder (kept)")
    arguments = parser.parse_args()
    if arguments.command == 'racing':
        racing_report(arguments.bags)
        return
    with tempfile.TemporaryDirectory() as scratch:
        folder = pathlib.Path(arguments.keep or scratch)
        folder.mkdir(parents=True, exist_ok=True)
        if arguments.command == 'task4-structure':
            task, engine = task4_structure(arguments.structure, folder), arguments.engine
            seed = 1 if arguments.seed is None else arguments.seed
        else:
            task, engine = TASKS / 'task5.yaml', 'mujoco'
            seed = 101 if arguments.seed is None else arguments.seed
        bag = folder / f'{arguments.command}-seed{seed}'
        figures = timed_run(task, arguments, engine, seed, bag)
        report(arguments.command, figures, bag, arguments)


if __name__ == '__main__':
    main()
