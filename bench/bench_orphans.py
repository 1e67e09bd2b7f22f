"""
Sweep: SIGKILL `hand-codesign run` at many moments; count the processes that outlive it.

The runner of a Task 5 run (2 evaluators) is killed at --kills moments spread from the start of
its first process to --latest s later, well into the run (and with --sigterm terminated at as
many); for each, how many of the run's processes were seen, how many still ran GRACE s later,
and how long the last one took to end. test/ros/test_orphans.py checks four moments in the suite.

Usage: python bench/bench_orphans.py [--kills 10] [--latest 5.0] [--sigterm]
"""

import argparse
import pathlib
import signal
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / 'test' / 'helpers'))

from run_kills import describe  # noqa: E402, I100: a helper of the tests, not a package
from run_kills import kill_run  # noqa: E402
from run_kills import running  # noqa: E402
from run_kills import survivors  # noqa: E402

GRACE = 5.0


def sweep(kills, latest, how):
    """Kill a run at `kills` moments from 0 to `latest` s; return the orphans' count."""
    orphans = 0
    with tempfile.TemporaryDirectory() as folder:
        for index in range(kills):
            moment = latest * index / max(1, kills - 1)
            seen, _ = kill_run(pathlib.Path(folder) / f'run{index}', after_seconds=moment,
                               how=how)
            killed = time.monotonic()
            while any(running(process) for process in seen) and (
                    time.monotonic() - killed < GRACE):
                time.sleep(0.02)
            ended = time.monotonic() - killed
            left = survivors(seen, 0.0)
            orphans += len(left)
            outcome = (f', all gone after {ended:.2f} s' if not left
                       else ':\n' + describe(left))
            print(f'{how.name} at {moment:4.1f} s: {len(seen)} processes seen, {len(left)} '
                  f'left after {GRACE:g} s{outcome}', flush=True)
            for process in left:   # leave nothing behind either way
                process.kill()
    return orphans


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--kills', type=int, default=10)
    parser.add_argument('--latest', type=float, default=5.0,
                        help='s from the first process to the last kill')
    parser.add_argument('--sigterm', action='store_true', help='also SIGTERM at each moment')
    arguments = parser.parse_args()
    orphans = sweep(arguments.kills, arguments.latest, signal.SIGKILL)
    if arguments.sigterm:
        orphans += sweep(arguments.kills, arguments.latest, signal.SIGTERM)
    print(f'orphans: {orphans}')
    return 1 if orphans else 0


if __name__ == '__main__':
    sys.exit(main())
