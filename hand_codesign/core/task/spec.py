"""
The Task: one frozen value holding a whole task, built by the reader and checked by the checks.

Its parts (and TaskError) are in hand_codesign.core.task.parts; every key of a task file is a
field declared with core.task.schema.key, here or there (docs/TASK.md lists them).
"""

import dataclasses
from dataclasses import dataclass
from typing import Optional, Tuple

from hand_codesign.core.design import Design
from hand_codesign.core.task.checks import check_task
from hand_codesign.core.task.parts import (ALGORITHMS, ArchiveSpec, EarlyTerminationSpec,
                                           FRONT_CHOICES, GoalSpec, HandSpec, HierarchySpec,
                                           MorphologySpec, ObjectSpec, PhysicsSpec, PolicySpec,
                                           RandomizationSpec, TaskError, TorquePenaltySpec,
                                           WeightsSpec, WorldsSpec)
from hand_codesign.core.task.schema import GIVEN, key
from hand_codesign.core.task.variant import Variant
import numpy as np

# the coordinates of its Variant a Task reads and replace() changes by name
VARIANT_COORDINATES = ('horizon', 'stage', 'held_out', 'world_draw')


@dataclass(frozen=True)
class Task:
    """A whole task: the task file's keys (docs/TASK.md), and where it came from."""

    name: str = key('identifies the task in runs, bags and plots', 'text', positive=True)
    seed: int = key('seeds the world states and the optimizer', 'integer', minimum=0)
    time_step: float = key('the physics step', 'number', unit='s', positive=True)
    duration: float = key('the simulated time of one rollout (a whole number of steps)',
                          'number', unit='s', positive=True)
    object_spec: ObjectSpec = key('the object the hand manipulates, nominal', 'section',
                                  section=ObjectSpec, yaml='object')
    hand: HandSpec = key('where the hand is, and the sizes the genome does not optimize',
                         'section', section=HandSpec)
    structure: Tuple[int, ...] = key(
        'joints per finger, e.g. [2, 2]', 'structure', yaml='hand.structure', default=GIVEN,
        default_text="the hierarchy's start")
    goals: GoalSpec = key('what the object must do: position and orientation goals (III.C)',
                          'section', section=GoalSpec, read='goals')
    randomization: RandomizationSpec = key(
        'domain randomization: each world draws every quantity uniformly in its range',
        'section', section=RandomizationSpec)
    num_world_states: int = key('the randomized worlds every candidate is evaluated on',
                                'integer', yaml='world_states', old='num_world_states')
    morphology: MorphologySpec = key(
        'the hand parameters (III.B): each a setting {fixed: v}, {bounds: [l, u]}, '
        '{delta: [l, u]} or seed', 'section', section=MorphologySpec)
    policy: PolicySpec = key('the control policy and the bounds of its values', 'section',
                             section=PolicySpec)
    algorithm: str = key('the optimizer: CMA-ES on the weighted sum, MO-CMA-ES on the Pareto '
                         'front, CMA-ES with restarts, or quality diversity', 'choice',
                         choices=ALGORITHMS, yaml='optimizer.algorithm')
    iterations: int = key('generations (per hand structure)', 'integer',
                          yaml='optimizer.iterations')
    population: int = key('candidates per generation', 'integer', yaml='optimizer.population')
    initial_sigma: float = key('the initial step size, in the normalized genome space',
                               'number', positive=True, default=0.1,
                               yaml='optimizer.initial_sigma')
    # generations without improvement after which ipop-cma / bipop-cma restart
    # (core.search.restarts); None: their default window
    restart_stagnation: Optional[int] = key(
        'ipop-cma, bipop-cma: generations without improvement that end a CMA-ES instance',
        'integer', default=None, default_text="pycma's window",
        yaml='optimizer.restart_stagnation')
    # not in the paper beyond 'normalized' (III.C); the search is the same either way, only the
    # design it returns differs
    front_choice: str = key(
        "mocma: the design of the final Pareto front the run returns: 'normalized', the one "
        'closest to zero with each objective min-max normalized over the front (III.C), or '
        "'weighted', the one with the least weighted sum of the task's weights", 'choice',
        choices=FRONT_CHOICES, default='normalized', yaml='optimizer.front_choice')
    # the archive of cma-mae / cma-me (core.search.quality_diversity); None: ArchiveSpec's defaults
    archive: Optional[ArchiveSpec] = key(
        'cma-mae, cma-me: the archive of designs, a grid over two descriptors', 'section',
        section=ArchiveSpec, default=None, default_text='the defaults of its keys',
        yaml='optimizer.archive')
    weights: WeightsSpec = key('the weights of the weighted-sum fitness', 'section',
                               section=WeightsSpec, default={}, field_default=WeightsSpec())
    physics: PhysicsSpec = key("the physics engine or engines and Bullet's settings (defaults: "
                               "Table I's runs)", 'section', section=PhysicsSpec, default={},
                               field_default=PhysicsSpec(), read='physics')
    worlds: WorldsSpec = key('how the worlds score a candidate and which worlds it meets',
                             'section', section=WorldsSpec, default={},
                             field_default=WorldsSpec())
    torque_penalty: Optional[TorquePenaltySpec] = key(
        'eq. (2): a penalty on torques above a threshold', 'section', section=TorquePenaltySpec,
        default=None)
    early_termination: Optional[EarlyTerminationSpec] = key(
        'eq. (6): stop a rollout whose goals miss by more than a margin', 'section',
        section=EarlyTerminationSpec, default=None, read='early_termination')
    hierarchy: Optional[HierarchySpec] = key(
        'search hand structures bottom-up (Fig. 1)', 'section', section=HierarchySpec,
        default=None)
    seed_design: Optional[Design] = key(
        'a starting design (seeded search, Tasks 1 and 2): inline, or a file relative to the '
        'task file', 'custom', read='seed_design_of', default=None,
        values='a design mapping (below), or a file name')
    # YAML `two_stage: true`: stage 1 optimizes on the nominal world only, stage 2 with the
    # randomization, starting from stage 1's result (core.search.stages).
    two_stage: bool = key('stage 1 on the nominal world only, then stage 2 on the randomized '
                          "worlds from stage 1's result (Tasks 1 and 2)", 'boolean',
                          default=False)
    # Not in the YAML: which version of the run's task this is (core.task.variant), set by the
    # search and carried in the Candidate message: its horizon, stage, held-out worlds and
    # resampled draw (read as task.horizon, task.stage, task.held_out, task.world_draw). The
    # variant's structure and world states are applied to `structure` and `num_world_states`,
    # so here they stay () and 0.
    variant: Variant = Variant()
    description: str = key('free text', 'text', default='', default_text='empty')
    source: str = '<task>'
    source_text: str = ''

    @property
    def num_steps(self):
        """Return the physics steps of one rollout."""
        return int(round(self.duration / self.time_step))

    @property
    def objective_names(self):
        """Return ('position_1', ..., 'orientation_1', ...): the objective vector's names."""
        return (tuple(f'position_{i + 1}' for i in range(len(self.goals.position)))
                + tuple(f'orientation_{i + 1}' for i in range(len(self.goals.orientation))))

    @property
    def objective_weights(self):
        """Return the fitness weights aligned with objective_names (w_p, then w_r)."""
        return np.array([self.weights.position] * len(self.goals.position)
                        + [self.weights.orientation] * len(self.goals.orientation))

    @property
    def horizon(self):
        """Return the sub-problem's horizon in seconds it is evaluated on, or None for none."""
        return self.variant.horizon if self.variant.horizon else None

    @property
    def stage(self):
        """Return its stage: 0 a single-stage task, 1 the nominal world, 2 the randomized."""
        return self.variant.stage

    @property
    def held_out(self):
        """Return whether its worlds come from the held-out stream (core.sim.worlds)."""
        return self.variant.held_out

    @property
    def world_draw(self):
        """Return its worlds' draw: 0 the run's fixed worlds, k >= 1 the k-th resampled one."""
        return self.variant.world_draw

    def replace(self, **changes):
        """
        Return a copy with some fields changed, validated like a loaded task.

        Typical: task.replace(seed=3, iterations=5, population=8, num_world_states=4,
        structure=(1, 2)). `horizon` (None: none), `stage`, `held_out` and `world_draw` change
        its variant. source_text stays the text as loaded.
        """
        coordinates = {name: changes.pop(name) for name in VARIANT_COORDINATES
                       if name in changes}
        if coordinates:
            if coordinates.get('horizon', 0.0) is None:
                coordinates['horizon'] = 0.0
            variant = changes.get('variant', self.variant)
            changes['variant'] = dataclasses.replace(variant, **coordinates)
        unknown = sorted(set(changes) - {f.name for f in dataclasses.fields(self)})
        if unknown:
            raise TaskError(f'{self.source}: {unknown[0]}: not a Task field')
        if 'structure' in changes:
            changes['structure'] = tuple(changes['structure'])
        task = dataclasses.replace(self, **changes)
        check_task(task)
        return task
