"""
Where a run's best design leaves the object on the plane, against where the world put it.

    python tools/final_offsets.py BAG [BAG ...] [--unseen 1000]

Each bag's best design is simulated on N unseen worlds (core.experiments.measures, as `reproduce`
and
`analyze --unseen` measure it). Per axis of the plane, x and y of the world, it prints the
share of worlds whose final offset from the last position goal is below 5 mm, and the
least-squares slope and the correlation of the object's final position on the world's start
offset along that axis. A slope near 1 with a high correlation says that the hand leaves the
object where the world put it along that axis: a part of the error no design of that hand
removes, since the hand cannot tell where the world put it.
"""

import argparse

from hand_codesign.analysis.campaign import final_design
from hand_codesign.core.experiments.measures import measure_worlds, unseen_world_states
import numpy as np

TOLERANCE = 0.005  # m


def axis_rows(measures, worlds):
    """Return [(axis, share within, slope, correlation)] of the plane's two axes."""
    rows = []
    for index, axis in enumerate('xy'):
        start = np.array([world.position_delta[index] for world in worlds])
        final = measures.final_positions[:, index]
        slope = np.polyfit(start, final, 1)[0]
        correlation = np.corrcoef(start, final)[0, 1]
        within = np.mean(measures.errors[axis] < TOLERANCE)
        rows.append((axis, float(within), float(slope), float(correlation)))
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('bags', nargs='+', help='bags of finished runs')
    parser.add_argument('--unseen', type=int, default=1000, help='unseen worlds (1000)')
    arguments = parser.parse_args()
    for bag in arguments.bags:
        task, x, _ = final_design(bag)
        worlds = unseen_world_states(task, arguments.unseen)
        measures = measure_worlds(x, task, worlds)
        plane = np.mean(measures.errors['plane'] < TOLERANCE)
        print(f'{bag}: seed {task.seed}, {arguments.unseen} unseen worlds; within 5 mm in the '
              f'plane {100 * plane:.1f} %')
        for axis, within, slope, correlation in axis_rows(measures, worlds):
            print(f'  along {axis}: within 5 mm {100 * within:.1f} %; final position on the '
                  f"start's offset: slope {slope:.2f}, correlation {correlation:.2f}")


if __name__ == '__main__':
    main()
