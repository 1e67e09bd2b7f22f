"""
Beyond the paper, on Task 6: the levers of levers-task5, and levers of Task 6's own hands.

The same levers of the search as levers-task5 on the hand above the box (`task6.yaml`); the
presets' lever: the hand turned to squeeze along the goal's diagonal (`task6_diagonal.yaml`),
also run with other choices of its preset changed (gravity compensation, finger friction,
torque bound, finger placement) and on the smaller half of the boxes alone, and on which
CMA-MAE also spans its archive by the outcome limit_rest (`cma-mae-limit-rest-diagonal`);
and levers on Task 6's paper hand (the palm beside the box, `cma-palm-beside-*`), among which
the worst quarter of the worlds was chosen on tuning seeds 1 to 3 to lift its tail, and
probes of it on the hardest boxes to turn alone; and that hand with the palm's placement searched
with the rest of the design (`cma-palm-beside-placed`). Not part of `reproduce all`.
"""

import math

from hand_codesign.campaign.experiment import Configuration
from hand_codesign.campaign.experiment import Experiment
from hand_codesign.campaign.registry import add
from hand_codesign.campaign.shared import FIVE_TIMES_TORQUE
from hand_codesign.campaign.shared import lever_budgets
from hand_codesign.campaign.shared import lever_configurations
from hand_codesign.campaign.shared import LEVER_WORLDS
from hand_codesign.campaign.shared import palm_beside_configuration
from hand_codesign.campaign.shared import placement_options
from hand_codesign.campaign.shared import preset_lever_configurations
from hand_codesign.campaign.shared import RESAMPLED
from hand_codesign.campaign.shared import WORST_QUARTER
from hand_codesign.core.experiments.measures import ORIENTATION_01

# A user's box around the palm beside the box (the pinned preset's 7.5 cm from it): 6.5 to 9 cm
# from the box, 2 cm to either side, at the preset's height, turned up to an eighth of a turn
# either way about the vertical
PLACEMENT_BESIDE = placement_options(((-0.09, -0.065), (-0.02, 0.02), (0.015, 0.015)),
                                     (-math.pi / 4, math.pi / 4))


def diagonal_hand_configurations():
    """
    Return CMA-ES on Task 6's diagonal hand with one more choice of its preset changed.

    Where the paper gives no value: the torque policy's gravity compensation (Sec. III offers
    it) and the fingers' friction (a low one lets a squeezed box slide round to the face
    across the push). Beyond Table I: its torque bound five times larger, to see whether the
    fingers' strength is what limits the squeeze. And a probe, not a preset: the smaller half
    of the boxes alone (scales 0.5 to 1), trained and measured there, to see whether the
    hand can turn them at all when it need not also turn the larger ones. Last, the fingers
    placed closer to the box, 6 and 4.5 cm from its centre instead of the pinned preset's 8.5
    (beside the largest box's corner): above the larger boxes, they must start splayed
    outwards to clear them, and reach the smaller ones with less of Table I's torque.
    """
    variants = (('gravity', (('policy.gravity_compensation', True),)),
                ('friction-0.2', (('morphology.friction.fixed', 0.2),)),
                ('torque-0.05', FIVE_TIMES_TORQUE),
                ('smaller-boxes', (('randomization.scale', (0.5, 1.0)),)),
                ('fingers-60mm', (('morphology.finger_position_x.fixed', (-0.06, 0.06)),)),
                ('fingers-45mm', (('morphology.finger_position_x.fixed', (-0.045, 0.045)),)))
    return tuple(Configuration(f'cma-diagonal-{name}', 'task6_diagonal.yaml', 'cma',
                               LEVER_WORLDS, 'torque', options)
                 for name, options in variants)


def palm_beside_lever_configurations():
    """
    Return CMA-ES on Task 6's paper hand (the palm beside the box) with one lever each.

    At Table I's budget its designs miss Task 6's target in a tail of worlds, the large
    boxes (scales 1.5 to 2) most. The levers that could lift that tail inside the paper's
    design space and budget: the worst quarter of the worlds as each candidate's score,
    worlds resampled each generation, both at once, a larger initial step, and the palm
    placed 1 cm further from the box or 0.5 cm closer (its face then 3 mm beyond the
    farthest corner of the largest box turned to the goal; the fixed hand's placement is our
    reading of Table I, as are its axes). Chosen on tuning seeds 1 to 3. After the choice,
    the best lever (the worst quarter) with the third (the closer palm; the second,
    resampled worlds, is paired above), on the same seeds: it did worse than either
    (docs/results/levers-task6/README.md).
    """
    palm_70mm = (('hand.base_position', (-0.07, 0.0, 0.015)),)
    variants = (('worst25', WORST_QUARTER), ('resample', RESAMPLED),
                ('worst25-resample', WORST_QUARTER + RESAMPLED),
                ('sigma-0.2', (('optimizer.initial_sigma', 0.2),)),
                ('palm-85mm', (('hand.base_position', (-0.085, 0.0, 0.015)),)),
                ('palm-70mm', palm_70mm), ('palm-70mm-worst25', palm_70mm + WORST_QUARTER))
    return tuple(Configuration(f'cma-palm-beside-{name}', 'task6_palm_beside.yaml', 'cma',
                               LEVER_WORLDS, 'torque', options)
                 for name, options in variants)


def palm_beside_probe_configurations():
    """
    Return probes, not presets: Task 6's paper hand trained and measured on the hardest boxes.

    At Table I's budget the designs fail in the worlds whose box the plane holds hardest
    against a turn: large, heavy and of high friction at once (the friction torque grows with
    each). The hardest corner of Table I's ranges (scale 1.75 to 2, mass 1.35 to 1.5 times,
    friction +0.025 to +0.05), trained and measured there alone, shows whether the hand can
    turn those boxes at all within Table I's torque bound; and, beyond Table I, with five
    times that bound, whether the fingers' strength is what stops it.
    """
    corner = (('randomization.scale', (1.75, 2.0)), ('randomization.mass', (1.35, 1.5)),
              ('randomization.friction', (0.025, 0.05)))
    return (Configuration('cma-palm-beside-hardest-boxes', 'task6_palm_beside.yaml', 'cma',
                          LEVER_WORLDS, 'torque', corner),
            Configuration('cma-palm-beside-hardest-boxes-torque-0.05', 'task6_palm_beside.yaml',
                          'cma', LEVER_WORLDS, 'torque', corner + FIVE_TIMES_TORQUE))


def palm_beside_placed_configuration():
    """Return CMA-ES on Task 6's paper hand with the palm's place and turn searched."""
    return Configuration('cma-palm-beside-placed', 'task6_palm_beside.yaml', 'cma',
                         LEVER_WORLDS, 'torque', PLACEMENT_BESIDE)


@add
def levers_task6():
    """Return the experiment: Task 6's levers, within 0.1 rad."""
    return Experiment(
        'levers-task6',
        'beyond the paper: Task 6 (torque), the same levers as levers-task5; and the hand '
        "turned to squeeze along the goal's diagonal, its fingers directly opposite; on that "
        'hand, gravity compensation, a low finger friction and (beyond Table I) five times '
        'its torque bound, its fingers placed closer to the box; and that hand trained and '
        'measured on the smaller half of the boxes alone; and the pinned hand (the palm '
        'beside the box) alone, on the worst quarter of its worlds, on worlds resampled '
        'each generation, both, with an initial step of 0.2, its palm 7 or 8.5 cm from '
        'the box, and its palm 7 cm from the box on the worst quarter; and, as probes, that '
        'hand trained and measured on the hardest boxes to turn (large, heavy, of high '
        "friction), with Table I's torque bound and five times it; and the pinned hand with "
        "the palm's place and turn searched",
        lever_configurations('task6.yaml')
        + preset_lever_configurations('task6_diagonal.yaml', 'diagonal')
        + diagonal_hand_configurations() + (palm_beside_configuration('task6'),)
        + palm_beside_lever_configurations() + palm_beside_probe_configurations()
        + (palm_beside_placed_configuration(),),
        ORIENTATION_01,
        lever_budgets(128),
        convergence=True, beyond_paper=True)
