"""
Where a Task 4 design misses: its unseen worlds in sixths of the box's starting turn error.

    python docs/results/task4-structures/by_start.py MEASURES.json ...

MEASURES.json is a campaign's `measures/CONFIGURATION-seedN.json` (written by `hand-codesign
reproduce`). For each sixth of the worlds, ordered by how far the box starts from the goal's
turn (rad), it prints the share within the pose (5 mm in the plane and 0.1 rad at once) and the
median final turn error (rad): misses spread evenly over the sixths come from where the design
leaves the box, not from the worlds that start far.
"""

import json
import sys

import numpy as np

PLANE_TOLERANCE = 0.005   # m
TURN_TOLERANCE = 0.1      # rad
PARTS = 6


def by_start(path):
    """Return [(start low, start high, share within the pose, median final turn error)]."""
    with open(path, encoding='utf-8') as handle:
        worlds = json.load(handle)['worlds']
    final = np.asarray(worlds['errors']['orientation'])
    plane = np.asarray(worlds['errors']['plane'])
    start = np.asarray(worlds['initial_errors']['orientation'])
    within = (final < TURN_TOLERANCE) & (plane < PLANE_TOLERANCE)
    return [(start[part].min(), start[part].max(), within[part].mean(), np.median(final[part]))
            for part in np.array_split(np.argsort(start), PARTS)]


def main(paths):
    """Print each measures file's sixths."""
    for path in paths:
        print(path)
        for low, high, share, median in by_start(path):
            print(f'  start {low:.2f}-{high:.2f} rad: within the pose {share:.0%}, '
                  f'final turn error median {median:.3f} rad')
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
