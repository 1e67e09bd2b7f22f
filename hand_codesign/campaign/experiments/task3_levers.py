"""
Beyond the paper: search levers for Task 3, where doing nothing is the best score a search finds.

Task 3 (turn a 15 cm capsule lying on the palm by 90 degrees about the vertical in 2 s, keeping
its position, a three-finger hand from scratch) with the paper's early termination grows its
horizon from 0.1 s and stops growing at 0.4 s, where the goal's turn first leaves the margin a
capsule that has not moved stays within: every candidate is then scored on how little it
disturbs the capsule, and a hand whose fingers stand clear of it wins. These configurations
keep the task and its measure and change the search: MO-CMA-ES as Table I (the paper's
configuration), CMA-ES on the weighted sum, each with early termination and on whole motions
(no early termination, so no horizon), BIPOP-CMA-ES (restarts, alternately with larger
populations and smaller steps) on whole motions, and CMA-MAE on whole motions over the turn the
capsule makes (the outcome `turn`, core.outcomes) and the fingers' length: an archive that keeps
the best hand of each turn apart, so the hands that turn the capsule further are not lost to
those that hold it still. Each a lever, reported as such. Last, our reading of the hand
questioned: `task3_clear_sweep.yaml` places the fingers where the capsule's turn does not pass
(in task3.yaml two of the three stand in its path), searched as Table I (`mocma-clear`) and by
CMA-ES on whole motions (`cma-whole-clear`).
"""

from hand_codesign.campaign.experiment import budgets
from hand_codesign.campaign.experiment import Configuration
from hand_codesign.campaign.experiment import Experiment
from hand_codesign.campaign.registry import add
from hand_codesign.core.experiments.measures import ORIENTATION_01

PRESET = 'task3.yaml'
# the fingers' places read clear of the path the capsule's 90-degree turn sweeps
CLEAR_SWEEP = 'task3_clear_sweep.yaml'
WORLDS = 16  # Table I's world states for Task 3
WHOLE_MOTIONS = (('early_termination', None),)  # no early termination: no horizon either
# the archive's grid: the capsule's turn (0.5 is the goal's 90 degrees) in 20 cells of 9
# degrees, so that hands a few degrees apart keep apart, by the fingers' length in 5
BY_TURN = (('optimizer.archive.descriptors', ('turn', 'finger_length')),
           ('optimizer.archive.cells', (20, 5)))


@add
def task3_levers():
    """Return the experiment: Task 3 with and without early termination, three optimizers."""
    return Experiment(
        'task3-levers',
        'beyond the paper: Task 3 (turn a capsule 90 degrees, from scratch) with MO-CMA-ES as '
        'Table I and CMA-ES, each with early termination and on whole motions, BIPOP-CMA-ES '
        '(restarts) on whole motions, CMA-MAE over the turn achieved on whole motions, and '
        'the fingers placed clear of the path of the turn (MO-CMA-ES; CMA-ES, whole motions)',
        (Configuration('mocma', PRESET, 'mocma', WORLDS, 'torque'),
         Configuration('cma', PRESET, 'cma', WORLDS, 'torque'),
         Configuration('mocma-whole', PRESET, 'mocma', WORLDS, 'torque', WHOLE_MOTIONS),
         Configuration('cma-whole', PRESET, 'cma', WORLDS, 'torque', WHOLE_MOTIONS),
         Configuration('bipop-cma-whole', PRESET, 'bipop-cma', WORLDS, 'torque',
                       WHOLE_MOTIONS),
         Configuration('cma-mae-turn-whole', PRESET, 'cma-mae', WORLDS, 'torque',
                       WHOLE_MOTIONS + BY_TURN),
         Configuration('mocma-clear', CLEAR_SWEEP, 'mocma', WORLDS, 'torque'),
         Configuration('cma-whole-clear', CLEAR_SWEEP, 'cma', WORLDS, 'torque', WHOLE_MOTIONS)),
        ORIENTATION_01, budgets((3, 8, 100, 1), (60, 40, 1000, 2), (1000, 250, 1000, 5)),
        beyond_paper=True)
