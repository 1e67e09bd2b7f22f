"""
Which unseen worlds a campaign's designs fail on: the share within per band of one quantity.

    python tools/within_by_world.py results/levers-task6-reduced levers-task6 \
        [--quantity scale] [--bands 0.5 0.75 1 1.25 1.5 2] [--seeds 5 | 101-105]

Reads the campaign's cached measures (no simulation): each run's final errors on its unseen
worlds, which `core.experiments.measures.unseen_world_states` draws again from the run's seed and
the task's ranges. Per configuration, the unseen worlds of its seeds are pooled and split by the
quantity (core.sim.worlds.QUANTITIES: position_x, position_y, orientation, friction, scale,
mass) into the bands given; each band gets its worlds and its share within the tolerance.
The derived quantity turn_friction is the box's friction times its mass times its scale, as a
factor of the nominal box's: the friction torque with which the plane resists turning the box
about the vertical grows with each of the three.
"""

import argparse
import sys

from hand_codesign.analysis.campaign import load_measures
from hand_codesign.core.experiments.catalog import EXPERIMENTS, parse_seeds
from hand_codesign.core.experiments.measures import shares_in_bands, unseen_world_states
from hand_codesign.core.experiments.robustness import world_values
from hand_codesign.core.sim.worlds import QUANTITIES
from hand_codesign.core.task import load_task, TaskError
from hand_codesign.errors import closed_stdout_status
import numpy as np


TURN_FRICTION = 'turn_friction'


def world_quantity(world, quantity, nominal_friction):
    """Return one world's value of a quantity of QUANTITIES or of TURN_FRICTION."""
    if quantity == TURN_FRICTION:
        friction = (nominal_friction + world.friction_delta) / nominal_friction
        return friction * world.mass_factor * world.scale
    return world_values(world)[QUANTITIES.index(quantity)]


def pooled_worlds(out, configuration, records, quantity, kind):
    """Return (quantity values, errors) of a configuration's unseen worlds over its seeds."""
    task = load_task(f'{out}/tasks/{configuration.key}.yaml')
    values, errors = [], []
    for record in records:
        worlds = unseen_world_states(task.replace(seed=record['seed']), record['unseen_worlds'])
        values += [world_quantity(world, quantity, task.object_spec.friction) for world in worlds]
        errors += record['worlds']['errors'][kind]
    return np.array(values), np.array(errors)


def main():
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('out', help='campaign folder')
    parser.add_argument('experiment', choices=sorted(EXPERIMENTS))
    parser.add_argument('--quantity', default='scale', choices=QUANTITIES + (TURN_FRICTION,))
    parser.add_argument('--bands', type=float, nargs='+', default=[0.5, 0.75, 1, 1.25, 1.5, 2])
    parser.add_argument('--seeds', type=parse_seeds, default='5',
                        help='N (1 to N), A-B or A,B,...')
    arguments = parser.parse_args()
    experiment = EXPERIMENTS[arguments.experiment]
    tolerance = experiment.tolerance
    edges = arguments.bands
    measured = load_measures(arguments.out, experiment, arguments.seeds)
    if not any(measured.values()):
        sys.exit(f'within_by_world: {arguments.out}: no measures of {experiment.name} for these '
                 f'seeds (expected measures/<configuration>-seed<N>.json, written by '
                 f'`hand-codesign reproduce {experiment.name}`)')
    print(f'share within ({tolerance.describe()}) by {arguments.quantity}: '
          + ' | '.join(f'[{low:g}, {high:g})' for low, high in zip(edges, edges[1:])))
    width = max(len(key) for key, seeds in measured.items() if seeds)
    for configuration in experiment.configurations:
        if not measured[configuration.key]:
            continue
        values, errors = pooled_worlds(arguments.out, configuration,
                                       measured[configuration.key], arguments.quantity,
                                       tolerance.kind)
        cells = [f'{100 * share:3.0f} % of {worlds:4d}' if worlds else f'  - % of {worlds:4d}'
                 for _, _, worlds, share in shares_in_bands(values, errors < tolerance.limit,
                                                            edges)]
        print(f'{configuration.key:{width}s} ' + ' | '.join(cells))
    sys.stdout.flush()  # here, not at exit, where a reader gone would not be caught


if __name__ == '__main__':
    try:
        main()
    except TaskError as error:  # a campaign folder without its configuration's task file
        sys.exit(f'within_by_world: {error}')
    except BrokenPipeError as error:  # `python tools/within_by_world.py ... | head`
        sys.exit(closed_stdout_status(error))
