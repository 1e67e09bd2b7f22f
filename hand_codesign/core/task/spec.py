"""
The Task: one frozen value holding a whole task, built by the reader and checked by the checks.

Its parts (and TaskError) are in hand_codesign.core.task.parts; the schema is documented in
hand_codesign.core.task.
"""

import dataclasses
from dataclasses import dataclass
from typing import Optional, Tuple

from hand_codesign.core.design import Design
from hand_codesign.core.task.checks import check_task
from hand_codesign.core.task.parts import (ArchiveSpec, EarlyTerminationSpec, GoalSpec, HandSpec,
                                           HierarchySpec, MorphologySpec, ObjectSpec, PhysicsSpec,
                                           PolicySpec, RandomizationSpec, TaskError,
                                           TorquePenaltySpec, WeightsSpec, WorldsSpec)
from hand_codesign.core.task.variant import Variant
import numpy as np

# the coordinates of its Variant a Task reads and replace() changes by name
VARIANT_COORDINATES = ('horizon', 'stage', 'held_out', 'world_draw')


@dataclass(frozen=True)
class Task:
    """A whole task; see the module docstring for the YAML schema and units."""

    name: str
    seed: int
    time_step: float
    duration: float
    object_spec: ObjectSpec
    hand: HandSpec
    structure: Tuple[int, ...]
    goals: GoalSpec
    randomization: RandomizationSpec
    num_world_states: int
    morphology: MorphologySpec
    policy: PolicySpec
    algorithm: str
    iterations: int
    population: int
    initial_sigma: float = 0.1
    # generations without improvement after which ipop-cma / bipop-cma restart
    # (core.search.restarts); None: their default window
    restart_stagnation: Optional[int] = None
    # the archive of cma-mae / cma-me (core.search.quality_diversity); None: ArchiveSpec's defaults
    archive: Optional[ArchiveSpec] = None
    weights: WeightsSpec = WeightsSpec()
    physics: PhysicsSpec = PhysicsSpec()
    worlds: WorldsSpec = WorldsSpec()
    torque_penalty: Optional[TorquePenaltySpec] = None
    early_termination: Optional[EarlyTerminationSpec] = None
    hierarchy: Optional[HierarchySpec] = None
    seed_design: Optional[Design] = None
    # YAML `two_stage: true`: stage 1 optimizes on the nominal world only, stage 2 with the
    # randomization, starting from stage 1's result (core.search.stages).
    two_stage: bool = False
    # Not in the YAML: which version of the run's task this is (core.task.variant), set by the
    # search and carried in the Candidate message: its horizon, stage, held-out worlds and
    # resampled draw (read as task.horizon, task.stage, task.held_out, task.world_draw). The
    # variant's structure and world states are applied to `structure` and `num_world_states`,
    # so here they stay () and 0.
    variant: Variant = Variant()
    description: str = ''
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
