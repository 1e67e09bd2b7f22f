"""
Which unseen worlds a campaign's designs fail on: the share within per band of one quantity.

    hand-codesign reproduce levers-task6 --out results/levers-task6-reduced \
        --bands 0.5 0.75 1 1.25 1.5 2 [--quantity scale] [--seeds 5 | 101-105]

Reads the campaign's cached measures (no simulation): each run's final errors on its unseen
worlds, which `core.experiments.measures.unseen_world_states` draws again from the run's seed and
the task's ranges. Per configuration, the unseen worlds of its seeds are pooled and split by the
quantity (core.sim.worlds.QUANTITIES: position_x, position_y, orientation, friction, scale,
mass) into the bands given; each band gets its worlds and its share within the tolerance.
The derived quantity turn_friction is the box's friction times its mass times its scale, as a
factor of the nominal box's: the friction torque with which the plane resists turning the box
about the vertical grows with each of the three.
"""

from typing import List, Sequence

from hand_codesign.campaign.experiment import Experiment
from hand_codesign.campaign.folders import load_measures
from hand_codesign.core.experiments.measures import shares_in_bands, unseen_world_states
from hand_codesign.core.experiments.robustness import world_values
from hand_codesign.core.sim.worlds import QUANTITIES
from hand_codesign.core.task import load_task, TaskError
from hand_codesign.errors import UserError
import numpy as np


TURN_FRICTION = 'turn_friction'
BAND_QUANTITIES = QUANTITIES + (TURN_FRICTION,)


def world_quantity(world, quantity, nominal_friction):
    """Return one world's value of a quantity of QUANTITIES or of TURN_FRICTION."""
    if quantity == TURN_FRICTION:
        friction = (nominal_friction + world.friction_delta) / nominal_friction
        return friction * world.mass_factor * world.scale
    return world_values(world)[QUANTITIES.index(quantity)]


def pooled_worlds(out, configuration, records, quantity, kind):
    """Return (quantity values, errors) of a configuration's unseen worlds over its seeds."""
    # the campaign's pinned task is its record, as a bag's task is: an old key reads silently
    task = load_task(f'{out}/tasks/{configuration.key}.yaml', warn_old_names=False)
    values, errors = [], []
    for record in records:
        worlds = unseen_world_states(task.replace(seed=record['seed']), record['unseen_worlds'])
        values += [world_quantity(world, quantity, task.object_spec.friction) for world in worlds]
        errors += record['worlds']['errors'][kind]
    return np.array(values), np.array(errors)


def band_lines(out: str, experiment: Experiment, seeds: Sequence[int], quantity: str,
               edges: Sequence[float]) -> List[str]:
    """
    Return the bands table of a campaign folder: a header line, then a line per configuration.

    Args:
        out: the campaign folder (its measures/ and tasks/).
        experiment: the experiment the campaign ran.
        seeds: the seeds whose measures are pooled.
        quantity: one of BAND_QUANTITIES.
        edges: the bands' edges in the quantity's unit, ascending (k edges, k - 1 bands).

    Returns:
        lines of text, each band as 'share % of worlds'.

    Raises:
        UserError: an unknown quantity; a folder without measures of these seeds or without a
            configuration's task file.
    """
    if quantity not in BAND_QUANTITIES:
        raise UserError(f'--quantity: expected one of {", ".join(BAND_QUANTITIES)}; got '
                        f'{quantity!r}')
    tolerance = experiment.tolerance
    measured = load_measures(out, experiment, seeds)
    if not any(measured.values()):
        raise UserError(f'{out}: no measures of {experiment.name} for these seeds (expected '
                        f'measures/<configuration>-seed<N>.json, written by `hand-codesign '
                        f'reproduce {experiment.name}`)')
    lines = [f'share within ({tolerance.describe()}) by {quantity}: '
             + ' | '.join(f'[{low:g}, {high:g})' for low, high in zip(edges, edges[1:]))]
    width = max(len(key) for key, records in measured.items() if records)
    for configuration in experiment.configurations:
        if not measured[configuration.key]:
            continue
        try:
            values, errors = pooled_worlds(out, configuration, measured[configuration.key],
                                           quantity, tolerance.kind)
        except TaskError as error:  # a campaign folder without its configuration's task file
            raise UserError(str(error)) from None
        cells = [f'{100 * share:3.0f} % of {worlds:4d}' if worlds else f'  - % of {worlds:4d}'
                 for _, _, worlds, share in shares_in_bands(values, errors < tolerance.limit,
                                                            edges)]
        lines.append(f'{configuration.key:{width}s} ' + ' | '.join(cells))
    return lines
