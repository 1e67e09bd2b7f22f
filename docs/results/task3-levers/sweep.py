"""
Where Task 3's fingers stand against the path the capsule's turn sweeps, on the palm.

The goal turns a capsule lying on the palm about the vertical through its centre. A finger
rooted on the palm blocks that turn wherever its base comes within the capsule's radius plus a
segment's radius of the capsule's axis at some heading between the start and the goal: the
capsule cannot pass over a base. This prints, for a task file, the share of each finger's
position bounds (sampled uniformly, seed 0) clear of the whole sweep; and, for result files
of that task, where each design's finger bases stand (world x, y in cm) and the first heading
(rad from the start) at which one of them meets the capsule. Geometry only: the capsule is
the segment of its cylinder's length (caps excluded; a cap is the radius), the fingers are
their bases, nothing moves but the turn.

Usage (from the repository's root):
    python docs/results/task3-levers/sweep.py config/tasks/task3.yaml [RESULT.json ...]
"""

import argparse
import json
import sys

from hand_codesign.core.rotations import rotate, vertical_turn
from hand_codesign.core.task import TaskError
from hand_codesign.core.task.reader import load_task
import numpy as np

SAMPLES = 2000  # finger positions drawn per finger's bounds
HEADINGS = 300  # headings checked between the start and the goal


class Sweep:
    """The capsule's axis at each heading of its turn from the start to the goal, in the plane."""

    def __init__(self, task):
        spec = task.object_spec
        if spec.shape != 'capsule' or not task.goals.orientation:
            raise TaskError(f'{task.source}: expected a capsule and an orientation goal')
        self.task = task
        self.centre = np.array(spec.position[:2])
        axis = np.array(rotate(spec.orientation, (0.0, 0.0, 1.0))[:2])
        start = np.arctan2(axis[1], axis[0])
        turn = vertical_turn(spec.orientation, task.goals.orientation[-1].orientation)
        angles = start + np.linspace(0.0, turn, HEADINGS + 1)
        self.turn = turn
        self.directions = np.stack([np.cos(angles), np.sin(angles)], axis=1)
        self.half_length = spec.length / 2
        self.reach = spec.radius + task.hand.segment_radius

    def first_meeting(self, point):
        """
        Return the index of the first heading whose capsule meets base `point`, or None.

        A base the capsule lies against at the start stops it there if the turn moves the
        capsule towards it; if the turn moves it away, the base meets it only where the turn
        comes back to it (a finger resting against the capsule does not stop it turning away).
        """
        offset = np.asarray(point) - self.centre
        along = np.clip(self.directions @ offset, -self.half_length, self.half_length)
        distances = np.linalg.norm(offset - along[:, None] * self.directions, axis=1)
        met = distances < self.reach
        if met[0] and distances[1] <= distances[0]:
            return 0
        first_clear = int(np.argmin(met)) if met[0] else 0
        if met[0] and met.all():
            return None  # it turns away from the base and never leaves it: a base on the axis
        later = np.flatnonzero(met[first_clear:])
        return first_clear + int(later[0]) if len(later) else None

    def heading(self, index):
        """Return the turn (rad from the start) of heading `index`."""
        return float(self.turn * index / HEADINGS)


def base_point(task, x, z):
    """Return the world (x, y) of a finger base at palm position (x, z) (hand frame, m)."""
    hand = task.hand
    world = np.array(hand.base_position) + np.array(rotate(hand.base_orientation, (x, 0.0, z)))
    return world[:2]


def clear_shares(task, sweep):
    """Return per finger the share of its position bounds that no heading of the turn meets."""
    rng = np.random.default_rng(0)
    shares = []
    xs, zs = task.morphology.finger_position_x.values, task.morphology.finger_position_z.values
    for x_bounds, z_bounds in zip(xs, zs):
        points = zip(rng.uniform(x_bounds.lower, x_bounds.upper, SAMPLES),
                     rng.uniform(z_bounds.lower, z_bounds.upper, SAMPLES))
        shares.append(np.mean([sweep.first_meeting(base_point(task, x, z)) is None
                               for x, z in points]))
    return shares


def design_bases(task, result):
    """Return the world (x, y) of each finger base of a result file's design."""
    design = result['design']
    count = len(task.structure)
    return [base_point(task, design[f'finger{index}.position_x'],
                       design[f'finger{index}.position_z']) for index in range(count)]


def main(argv=None):
    """Print the clear share of each finger's bounds, then each result's first meeting."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('task')
    parser.add_argument('results', nargs='*', metavar='RESULT')
    arguments = parser.parse_args(argv)
    try:
        task = load_task(arguments.task)
        sweep = Sweep(task)
    except (OSError, TaskError) as error:
        sys.exit(f'sweep: {error}')
    print(f'{arguments.task}: turn {sweep.turn:+.3f} rad; capsule {sweep.half_length * 2:.3f} m '
          f'long, met within {sweep.reach * 100:.1f} cm of its axis')
    for index, share in enumerate(clear_shares(task, sweep)):
        print(f'finger {index}: {share:.1%} of its position bounds clear of the sweep')
    for path in arguments.results:
        try:
            bases = design_bases(task, json.loads(open(path).read()))
        except (OSError, ValueError, KeyError) as error:
            sys.exit(f'sweep: {path}: expected a result file of this task ({error})')
        meetings = [(sweep.first_meeting(point), index) for index, point in enumerate(bases)]
        met = [(heading, index) for heading, index in meetings if heading is not None]
        where = ', '.join(f'{index}: ({x * 100:+.1f}, {y * 100:+.1f})'
                          for index, (x, y) in enumerate(bases))
        first = (f'first met at {sweep.heading(min(met)[0]):+.3f} rad by finger {min(met)[1]}'
                 if met else 'clear of the whole turn')
        print(f'{path}: bases (cm) {where}; {first}')


if __name__ == '__main__':
    main()
