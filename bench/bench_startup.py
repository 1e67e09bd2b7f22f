"""
Benchmark of a run's start: from `hand-codesign run` to the first candidate sent.

Starts a tiny Task 5 run (1 generation of 4 candidates on 1 world) with 2 evaluators several
times and reads from each bag when the recorder received the first candidate; the time counts
from just before the command is launched (so it includes the interpreter's start, the imports
of every process, DDS discovery and the optimizer's wait for its evaluators). Prints each
start, the median and the best (target: < 3 s), with the load average: on a busy machine the
processes' imports wait for a core. Also printed: when the first heartbeat of an evaluator and
the first evaluation reached the bag, and a reference measured in the same run, between the
starts: a bare ROS 2 process (`python -c "import rclpy; rclpy.init(); ..."`, one node, exit).
The ratio of the medians says how many bare ROS starts a run's start costs, whatever the load.

Where the time goes (2-core machine, 2 evaluators; CPU seconds from `python -X importtime`
and `time.process_time`, wall seconds from traced runs under a load average of 7 to 9, where a
bare ROS 2 process took 0.6 to 1.4 s):
- the `hand-codesign run` process: interpreter, imports (0.2 s of CPU, numpy and yaml for the
  task) and the task's checks (0.01 s); under load it starts the first process 0.7 to 0.8 s
  after launch;
- each process imports rclpy and the messages (with numpy) for about 0.2 s of CPU, then its own
  code: in all 0.31 s for the recorder, 0.42 s for an evaluator (PyBullet itself 0.05 s),
  0.42 s for the optimizer (its search: cma, deap, the controller); rclpy.init and the node
  another 0.1 to 0.2 s each. Four such processes share the two cores: under load they are all
  up 1.6 to 2.2 s after they were started;
- the runner waited for the recorder before it started anything else, a core left idle
  meanwhile (1.1 to 1.9 s under load). Now recorder, evaluators and optimizer start side by
  side, and the optimizer sends nothing until the runner tells it (a line on its standard
  input) that the recorder records, so that the bag still gets every candidate from the first;
- DDS discovery: Fast DDS announces a new process 5 times in its first 0.5 s, then every 3 s.
  In 2 of 3 traced starts a process missed another's first announcements, and the two found
  each other 1.5 to 3 s later: the median of 4.4 s against a best of 1.6 s measured before.
  The run's processes now announce themselves 30 times in their first 3 s
  (hand_codesign/ros/fastdds_start.xml); no such wait was seen since;
- polling: an evaluator announced itself at its next heartbeat (0.5 s period) after its
  subscribers matched, and the optimizer started at its next tick (0.2 s) after that; both now
  act on the event itself (a publisher's matched event, the heartbeat's arrival);
- imports the start did not need: importlib.metadata, psutil, mcap's readers: an evaluator
  imported in 0.31 s of CPU instead of 0.42 s, the recorder in 0.25 s instead of 0.31 s.
  xml.sax.saxutils (URDF attributes; it imports urllib and http.client) is kept: about 20 ms
  once per process, not worth writing XML quoting again. The optimizer still imports DEAP
  (and through it moocore, urllib) also when it runs pycma's CMA-ES.

Measured with the code before these changes (commit c411ce1) and after, interleaved, 12 starts
each under a load average of 9.6: median 5.97 s before (4.5 bare ROS 2 starts, best 4.64 s),
3.87 s after (2.9 bare starts, best 1.93 s); in the calmer starts, where a bare ROS 2 process
took 0.6 to 0.8 s, 4.6 to 6.3 s before and 1.9 to 3.4 s after. Six more of each under a
load average of 4.5: 4.86 s before (5.1 bare starts), 2.64 s after (2.8). This benchmark alone
under a load average of 3.1: 1.81 s (bare ROS 2 start 0.55 s, ratio 3.3).

Usage: python bench/bench_startup.py [--repeats 5]
"""

import argparse
import os
import pathlib
import subprocess
import sys
import tempfile
import time

from hand_codesign.bag.reader import read_run
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
TASK_FILE = ROOT / 'config' / 'tasks' / 'task5.yaml'
BARE_ROS = ('import rclpy; rclpy.init(); node = rclpy.create_node("reference"); '
            'node.destroy_node(); rclpy.shutdown()')


def environment():
    return dict(os.environ, AMENT_PREFIX_PATH=os.environ.get('AMENT_PREFIX_PATH', sys.prefix))


def time_to_first_candidate(folder, index):
    """Run a tiny co-design; return seconds from launch to its first status, candidate, answer."""
    bag = pathlib.Path(folder) / f'start-{index}'
    command = [sys.executable, '-m', 'hand_codesign.cli', 'run', '--task', str(TASK_FILE),
               '--evaluators', '2', '--bag', str(bag), '--quiet', '--iterations', '1',
               '--population', '4', '--world-states', '1', '--seed', '1', '--domain-id', 'auto']
    launched = time.time()
    subprocess.run(command, check=True, cwd=ROOT, stdout=subprocess.DEVNULL, env=environment())
    record = read_run(bag)
    return tuple(np.min(table['log_time']) * 1e-9 - launched for table in (
        record.evaluator_status, record.candidates, record.evaluations))


def bare_ros_start():
    """Return the wall seconds of a bare ROS 2 process: interpreter, rclpy, one node, exit."""
    launched = time.perf_counter()
    subprocess.run([sys.executable, '-c', BARE_ROS], check=True, env=environment())
    return time.perf_counter() - launched


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--repeats', type=int, default=5)
    arguments = parser.parse_args()
    references, starts = [], []
    with tempfile.TemporaryDirectory() as folder:
        for index in range(arguments.repeats):
            references.append(bare_ros_start())
            starts.append(time_to_first_candidate(folder, index))
    heartbeats, times, evaluations = np.array(starts).T
    print(f'hand-codesign run to the first candidate sent, {arguments.repeats} starts '
          f'({time.strftime("%H:%M:%S")}, load average {os.getloadavg()[0]:.1f} on '
          f'{os.cpu_count()} cores)')
    print('  each     ' + '  '.join(f'{value:.2f}' for value in times) + ' s')
    print(f'  median   {np.median(times):.2f} s   best {min(times):.2f} s   (target < 3 s)')
    print(f'  first heartbeat recorded {np.median(heartbeats):.2f} s, first evaluation '
          f'{np.median(evaluations):.2f} s (medians)')
    print(f'reference: a bare ROS 2 process start (rclpy, one node), median '
          f'{np.median(references):.2f} s')
    print(f'  start-up / reference = {np.median(times) / np.median(references):.1f}')


if __name__ == '__main__':
    main()
