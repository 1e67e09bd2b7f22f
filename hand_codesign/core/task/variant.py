"""
Which version of a run's task a candidate is evaluated on: one frozen value, `Variant`.

A run has one task (its file's text and the run's overrides, core.run.runs); the search
evaluates its candidates on versions of it: another hand structure (the hierarchy), more worlds
(a structure's check), a shorter horizon (early termination's sub-problems), a stage (two-stage
tasks), the held-out worlds (the hierarchy's check) or a fresh draw of worlds (resampling).
A Variant says which, in one value: the search gives one to every candidate
(core.search.optimizers.Candidate.variant), the Candidate message carries its fields
(ros.conversions maps them to and from the message's flat fields, so bags keep their format),
the evaluator keys the tasks it builds by it (core.run.evaluation_jobs.job_key) and
`core.run.runs.run_task` applies it to the run's task.
"""

from dataclasses import dataclass
from typing import Tuple


@dataclass(frozen=True)
class Variant:
    """
    The coordinates of a version of the run's task; each default keeps the run's value.

    structure: joints per finger (); world_states: worlds to evaluate on, 0 the run's number;
    horizon: s of the sub-problem, 0.0 none; stage: 0 a single-stage task, 1 the nominal world
    only, 2 the randomized worlds; held_out: the worlds come from the held-out stream;
    world_draw: 0 the run's fixed worlds, k >= 1 the k-th resampled draw.
    """

    structure: Tuple[int, ...] = ()
    world_states: int = 0
    horizon: float = 0.0
    stage: int = 0
    held_out: bool = False
    world_draw: int = 0

    def task_changes(self):
        """Return the Task.replace changes that make the run's task this version of it."""
        changes = {}
        if self.structure:
            changes['structure'] = tuple(int(joints) for joints in self.structure)
        if self.world_states:
            changes['num_world_states'] = int(self.world_states)
        if self.horizon:
            changes['horizon'] = float(self.horizon)
        if self.stage:
            changes['stage'] = int(self.stage)
        if self.held_out:
            changes['held_out'] = True
        if self.world_draw:
            changes['world_draw'] = int(self.world_draw)
        return changes
