"""
Task 4's structures one at a time, each with Table I's per-structure budget (Fig. 3).

The hierarchy (task4-hierarchy) runs every structure from one finger with one joint to two
fingers with three joints and the three-finger hands grown from the best, each optimization
with Table I's 200 x 150 on 64 worlds: about a dozen structures, optimized twice, which does
not fit this machine. This experiment runs the structures Fig. 3 compares by name, each on its
own with the same budget, MO-CMA-ES as Table I says: the one-finger hand (1), which the paper
finds worst; the two two-finger hands (2,2) and (1,3), of which (1,3) "drastically
outperforms" (2,2); the smallest two-finger hand (1,1); and one three-finger hand, (1,1,2),
the hand a third finger grows from (1,1) and the best three-finger hand of the hierarchy's
reduced campaign. Each seed is one optimization (the paper optimizes each structure twice:
two seeds).

Beyond the paper, the same structures searched with CMA-ES on the weighted sum (w_p = 1,
w_r = 0.1, as Tasks 5 and 6) instead of MO-CMA-ES and its choice from the front: a lever,
reported as such. And the same structures in MuJoCo (keys ending in -mujoco), the physics a
Table I run of one structure fits in here (about twenty minutes against an hour and a half in
PyBullet on two cores): the engine is then part of the result, which holds in that engine.
And beyond the paper, (1,3) and (2,2) in MuJoCo with the palm's place and its turn about the
vertical searched with the rest of the design (keys ending in -placed-mujoco), so that the
hand's placement over the box is not only the preset's choice. Not part of `reproduce all`,
which runs the hierarchy itself.
"""

import math

from hand_codesign.campaign.experiment import budgets
from hand_codesign.campaign.experiment import Configuration
from hand_codesign.campaign.experiment import Experiment
from hand_codesign.campaign.registry import add
from hand_codesign.campaign.shared import placement_options
from hand_codesign.core.experiments.measures import ORIENTATION_01
from hand_codesign.core.experiments.measures import PLANE_5MM
from hand_codesign.core.experiments.measures import POSE

# Fig. 3's structures by name, in the order of the hierarchy (joints per finger)
STRUCTURES = ((1,), (1, 1), (1, 3), (2, 2), (1, 1, 2))
PRESET = 'task4_structure.yaml'
WORLDS = 64  # Table I's world states for Task 4's hierarchy
# the palm centre within 3 cm of the preset's over the box's start, 1 cm higher or lower (a
# finger of the mean length then ends 0.2 to 2.2 cm above the plane), turned up to 45 degrees
# either way about the vertical (the goal's turn)
PLACEMENT = placement_options(((-0.03, 0.03), (-0.03, 0.03), (0.072, 0.092)),
                              (-math.pi / 4, math.pi / 4))
PLACED_STRUCTURES = ((1, 3), (2, 2))


def structure_key(algorithm, structure, engine='pybullet'):
    """Return a configuration key such as 'mocma-1-3' for (1, 3) with MO-CMA-ES in PyBullet."""
    key = f'{algorithm}-' + '-'.join(str(joints) for joints in structure)
    return key if engine == 'pybullet' else f'{key}-{engine}'


def structure_configuration(algorithm, structure, engine='pybullet'):
    """Return the Configuration of one structure, optimized on its own with `algorithm`."""
    options = (('hand.structure', list(structure)),)
    if engine != 'pybullet':
        options += (('physics.engine', engine),)
    return Configuration(structure_key(algorithm, structure, engine), PRESET, algorithm,
                         WORLDS, 'torque', options)


def placed_configuration(structure):
    """Return MO-CMA-ES in MuJoCo on one structure with the palm's place and turn searched."""
    unplaced = structure_configuration('mocma', structure, 'mujoco')
    key = structure_key('mocma', structure) + '-placed-mujoco'
    return Configuration(key, PRESET, 'mocma', WORLDS, 'torque', unplaced.options + PLACEMENT)


@add
def task4_structures():
    """Return the experiment: Fig. 3's structures, each with Table I's per-structure budget."""
    return Experiment(
        'task4-structures',
        "Task 4 (turn a box 45 degrees, keep its position): Fig. 3's structures one at a "
        "time with Table I's per-structure budget, MO-CMA-ES (CMA-ES as a lever; the palm's "
        'place searched as another)',
        tuple(structure_configuration(algorithm, structure, engine)
              for engine in ('pybullet', 'mujoco') for algorithm in ('mocma', 'cma')
              for structure in STRUCTURES)
        + tuple(placed_configuration(structure) for structure in PLACED_STRUCTURES),
        POSE, budgets((2, 8, 100, 1), (60, 60, 1000, 3), (200, 150, 1000, 2)),
        also=(ORIENTATION_01, PLANE_5MM), beyond_paper=True)
