"""
The two stages of Tasks 1 and 2 (section IV): first without randomization, then with it.

A task with `two_stage: true` runs two optimizations in one run. Stage 1 evaluates every
candidate on the nominal world only (`task.replace(stage=1)`: core.sim.worlds gives the one world
without randomization); when its optimizer stops, stage 2 starts at stage 1's best design and
evaluates on the task's randomized worlds (`stage=2`). Each stage has the task's budget
(iterations, population); stage 1's optimizer uses the run's seed, stage 2's
`derived_seed(run seed, 2)`. Every candidate carries its stage (Candidate.stage), so any
evaluator, replay and analysis rebuild the task it was evaluated with, and the switch is a
function of the objectives told, so resume re-derives it by replaying them.

The run's result is stage 2's best design: stage 1's scores are on another set of worlds and
do not compare with it.
"""

from hand_codesign.core.search.factory import make_optimizer
from hand_codesign.core.search.optimizers import derived_seed
from hand_codesign.core.task.genome import genome_spec

STAGES = (1, 2)


class StagedSearch:
    """Stage 1 on the nominal world, then stage 2 on the randomized worlds; ask/tell."""

    def __init__(self, task, first_id=0):
        self.task = task
        self._tasks = {stage: task.replace(stage=stage) for stage in STAGES}
        self._size = genome_spec(task).size
        self.stage = 1
        self.seeds = {1: task.seed}
        self.stage_results = {}  # stage -> OptimizerResult of a finished stage
        self._optimizer = make_optimizer(self._tasks[1], self._size, first_id=first_id)

    @property
    def optimizer(self):
        """Return the optimizer of the current stage."""
        return self._optimizer

    @property
    def evaluation_task(self):
        """Return the task the current stage's candidates are evaluated with."""
        return self._tasks[self.stage]

    def ask(self):
        """Return the current stage's candidates (the same ones again until told)."""
        return self._optimizer.ask()

    def tell(self, results):
        """Tell the objectives of the candidates asked; start stage 2 when stage 1 stops."""
        self._optimizer.tell(results)
        if self.stage == 1 and self._optimizer.stop():
            self.stage_results[1] = self._optimizer.result
            self.stage = 2
            self.seeds[2] = derived_seed(self.task.seed, 2)
            self._optimizer = make_optimizer(
                self._tasks[2], self._size, first_id=self._optimizer.next_id,
                seed_x=self.stage_results[1].x, seed=self.seeds[2])
        elif self.stage == 2 and self._optimizer.stop():
            self.stage_results[2] = self._optimizer.result

    def stop(self):
        """Return why the search stopped (stage 2's optimizer), as a dict; empty while it runs."""
        if self.stage == 2 and self._optimizer.stop():
            return {'stage': 2, **self._optimizer.stop()}
        return {}

    @property
    def result(self):
        """Return the current stage's best design (stage 2's once it runs), or None."""
        return self._optimizer.result

    @property
    def next_id(self):
        """Return the id the next new candidate will get."""
        return self._optimizer.next_id
