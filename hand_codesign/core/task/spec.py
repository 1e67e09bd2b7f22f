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
import numpy as np


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
    # Not in the YAML: the horizon (s) of the sub-problem a candidate is evaluated on, set by
    # the search (hand_codesign.core.search.horizon) and carried in its Candidate message; None:
    # none.
    horizon: Optional[float] = None
    # YAML `two_stage: true`: stage 1 optimizes on the nominal world only, stage 2 with the
    # randomization, starting from stage 1's result (core.search.stages).
    two_stage: bool = False
    # Not in the YAML, set by the search and carried in the Candidate message like `horizon`:
    # the stage a candidate belongs to (0: a single-stage task; 1: the nominal world only; 2:
    # the randomized worlds), and held_out: the worlds are drawn from the held-out stream
    # (core.sim.worlds), disjoint from the training worlds, for a hierarchy structure's check.
    stage: int = 0
    held_out: bool = False
    # Not in the YAML either, carried in Candidate.world_draw: 0 evaluates on the run's fixed
    # worlds, k >= 1 on the k-th resampled draw (core.sim.worlds; worlds.resample: generation).
    world_draw: int = 0
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

    def replace(self, **changes):
        """
        Return a copy with some fields changed, validated like a loaded task.

        Typical: task.replace(seed=3, iterations=5, population=8, num_world_states=4,
        structure=(1, 2)). source_text stays the text as loaded.
        """
        unknown = sorted(set(changes) - {f.name for f in dataclasses.fields(self)})
        if unknown:
            raise TaskError(f'{self.source}: {unknown[0]}: not a Task field')
        if 'structure' in changes:
            changes['structure'] = tuple(changes['structure'])
        task = dataclasses.replace(self, **changes)
        check_task(task)
        return task
