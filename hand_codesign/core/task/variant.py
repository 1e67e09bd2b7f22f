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
`core.run.runs.run_task` applies it to the run's task: its structure and world states to the
task's own fields, the rest to `Task.variant`, the one field of a Task that its YAML has no key
for.
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
        """
        Return the Task.replace changes that make the run's task this version of it.

        Structure and world states go to the task's own fields (a default keeps the task's);
        the other coordinates become the task's variant, which the YAML has no key for.
        """
        changes = {}
        if self.structure:
            changes['structure'] = tuple(int(joints) for joints in self.structure)
        if self.world_states:
            changes['num_world_states'] = int(self.world_states)
        coordinates = Variant(horizon=float(self.horizon), stage=int(self.stage),
                              held_out=bool(self.held_out), world_draw=int(self.world_draw))
        if coordinates != Variant():
            changes['variant'] = coordinates
        return changes
