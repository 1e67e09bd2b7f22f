"""
Beyond the paper, on Task 5: the levers of a more reliable search, on the same evaluations.

The paper's algorithms against restarts (IPOP-, BIPOP-CMA-ES), the worst quarter of the
worlds (CVaR), worlds resampled each generation, quality diversity (CMA-MAE and its
archive's recommended design) and racing over the worlds (`cma-raced`, fewer rollouts:
core.search.racing); the reduced budget fixes every configuration's training worlds
(40 x 40 on 16 worlds). Also the presets' lever, a preset choice of ours revisited: the
position scored along the fingers' axis alone (`task5_along_x.yaml`; the tables give the
shares within 5 mm along x and along y beside the share in the plane), on which CMA-MAE also
spans its archive by an outcome of the rollouts (`cma-mae-limit-rest-along-x`: the joint-limit
span and limit_rest, core.outcomes); and the fixed hand read with the palm beside the box,
its fingers along x or along y. Not part of `reproduce all`.
"""

import math

from hand_codesign.campaign.experiment import Configuration
from hand_codesign.campaign.experiment import Experiment
from hand_codesign.campaign.registry import add
from hand_codesign.campaign.shared import lever_budgets
from hand_codesign.campaign.shared import lever_configurations
from hand_codesign.campaign.shared import LEVER_WORLDS
from hand_codesign.campaign.shared import palm_beside_configuration
from hand_codesign.campaign.shared import placement_options
from hand_codesign.campaign.shared import preset_lever_configurations
from hand_codesign.core.experiments.measures import ALONG_X_5MM
from hand_codesign.core.experiments.measures import ALONG_Y_5MM
from hand_codesign.core.experiments.measures import PLANE_5MM

# A user's box around the palm hung above the box (Task 5's preset at (0, 0, 0.15)): 3 cm
# either way in the plane, 2 cm up or down, and any turn about the vertical; a quarter turn
# either way spans them all, as the two-finger hand turned by half a turn is the same hand
# with its fingers swapped
PLACEMENT_ABOVE = placement_options(((-0.03, 0.03), (-0.03, 0.03), (0.13, 0.17)),
                                    (-math.pi / 2, math.pi / 2))


def placement_configurations():
    """
    Return CMA-ES with the palm's placement searched, on Task 5 and on a goal along y.

    And on the goal along y with three times the initial step (0.3 of every gene's range): the
    search starts from the middle of the placement's bounds, the hand as the preset turns it,
    where pushing the box only moves it away from a goal across the fingers' plane; a quarter
    turn is five of the default steps away.
    """
    return (Configuration('cma-placed', 'task5.yaml', 'cma', LEVER_WORLDS, 'torque',
                          PLACEMENT_ABOVE),
            Configuration('cma-goal-y', 'task5_goal_y.yaml', 'cma', LEVER_WORLDS, 'torque'),
            Configuration('cma-goal-y-placed', 'task5_goal_y.yaml', 'cma', LEVER_WORLDS,
                          'torque', PLACEMENT_ABOVE),
            Configuration('cma-goal-y-placed-sigma-0.3', 'task5_goal_y.yaml', 'cma',
                          LEVER_WORLDS, 'torque',
                          PLACEMENT_ABOVE + (('optimizer.initial_sigma', 0.3),)))


@add
def levers_task5():
    """Return the experiment: Task 5's levers, within 5 mm in the plane, along x and y."""
    return Experiment(
        'levers-task5',
        'beyond the paper: Task 5 (torque) with CMA-ES and MO-CMA-ES against restarts '
        '(IPOP-, BIPOP-CMA-ES), the worst quarter of the worlds (CVaR), worlds resampled '
        'each generation and quality diversity (CMA-MAE), on the same evaluations; and the '
        "position scored along the fingers' axis alone (x), where the hand can move the box",
        lever_configurations('task5.yaml')
        + preset_lever_configurations('task5_along_x.yaml', 'along-x')
        + (palm_beside_configuration('task5'),
           Configuration('cma-palm-beside-y', 'task5_palm_beside_y.yaml', 'cma', LEVER_WORLDS,
                         'torque'))
        + placement_configurations(), PLANE_5MM,
        lever_budgets(64), convergence=True, beyond_paper=True,
        also=(ALONG_X_5MM, ALONG_Y_5MM))
