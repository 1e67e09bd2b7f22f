"""
A run's whole search, driven one batch at a time: one optimization, or the hierarchy's chain.

The optimizer node, resume and analysis see every task the same way through `Search`:
`ask()` gives a batch of candidates, `batch_task` the task to evaluate them with (the
structure and, for the check of a structure's best design, the hierarchy's evaluation world
states), `tell()` takes id -> objectives, `stop()` says why it ended. With
early_termination.horizon the batch task also holds the sub-problem's horizon
(core.search.horizon), which grows from what `tell()` was told and which every candidate of the
batch carries. A task with `two_stage` runs core.search.stages.StagedSearch: each candidate also
carries its stage, and the horizon carries on from stage 1 into stage 2 (stage 2 starts at stage
1's design, which tracks the goals up to that horizon on the nominal world). A task with
`worlds: {resample: generation}` runs core.search.resampling.ResampledSearch: each candidate
carries its generation's draw of worlds (Candidate.world_draw), and a final check on the fixed
worlds chooses the run's result.
"""

import dataclasses
from typing import Any, Dict, List, Mapping, Optional

from hand_codesign.core.search.factory import make_optimizer
from hand_codesign.core.search.hierarchy import HierarchySearch
from hand_codesign.core.search.horizon import Horizon
from hand_codesign.core.search.optimizers import Candidate
from hand_codesign.core.search.resampling import ResampledSearch
from hand_codesign.core.search.stages import StagedSearch
from hand_codesign.core.task.genome import genome_spec
from hand_codesign.core.task.spec import Task


class Search:
    """
    The search of a task: its optimizer, or a HierarchySearch when the task has one.

    Driven as an ask/tell optimizer: `ask()` returns the batch, a list of
    core.search.optimizers.Candidate (an id, a generation, a normalized genome of shape
    (genome_spec(batch_task).size,) and the Variant of the task it is evaluated on);
    `batch_task` is that Task; `tell({id: objectives})` takes every candidate's objective
    vector (shape (objectives,), or an Evaluation); `stop()` returns why it ended ({} while it
    goes on). `tell` raises TellError (core.search.optimizers) for results that miss or add
    candidates of the batch.

    Args:
        task: a core.task.Task, the run's after its overrides.
        first_id: the id of its first candidate (a resumed run continues the ids).

    Raises:
        OptimizerError: for an algorithm or a setting its optimizer cannot take.
    """

    def __init__(self, task: Task, first_id: int = 0) -> None:
        self.task = task
        self._driver: Any
        if task.hierarchy is not None:
            self._driver = HierarchySearch(task, first_id=first_id)
        elif task.two_stage:
            self._driver = StagedSearch(task, first_id=first_id)
        elif task.worlds.resample == 'generation':
            self._driver = ResampledSearch(task, first_id=first_id)
        else:
            self._driver = make_optimizer(task, genome_spec(task).size, first_id=first_id)
        early = task.early_termination
        self._horizon = (Horizon(task) if early is not None and early.horizon is not None
                         and task.horizon is None else None)
        self._batch: Optional[List[Candidate]] = None

    @property
    def hierarchical(self):
        return isinstance(self._driver, HierarchySearch)

    @property
    def staged(self):
        return isinstance(self._driver, StagedSearch)

    @property
    def resampled(self):
        return isinstance(self._driver, ResampledSearch)

    @property
    def stage(self):
        """Return the stage of the batch of `ask()` (0 for a single-stage task)."""
        return self._driver.stage if self.staged else 0

    @property
    def optimizer(self):
        """Return the optimizer of the structure (or stage) being searched."""
        if self.hierarchical or self.staged or self.resampled:
            return self._driver.optimizer
        return self._driver

    @property
    def checking(self):
        """Return True when the batch is a check: a structure's best design, or resampling's."""
        return (self.hierarchical or self.resampled) and self._driver.checking

    @property
    def batch_task(self):
        """Return the task with which the batch of `ask()` is evaluated."""
        if self.staged:
            task = self._driver.evaluation_task
            return task if self._horizon is None else self._horizon.task_at(
                self._horizon.current, task)
        if self._horizon is not None:
            return self._horizon.batch_task
        return self._driver.evaluation_task if self.hierarchical or self.resampled else self.task

    @property
    def horizon(self):
        """Return the horizon in seconds of the batch of `ask()`, or None without one."""
        return None if self._horizon is None else self._horizon.current

    @property
    def horizons(self):
        """Return the horizon of every generation told so far (empty without one)."""
        return [] if self._horizon is None else list(self._horizon.history)

    def horizon_of(self, generation):
        """Return the horizon (s) generation `generation` was or is evaluated on; 0: none."""
        if self._horizon is None:
            return 0.0
        history = self._horizon.history
        return history[generation] if generation < len(history) else self._horizon.current

    def ask(self) -> List[Candidate]:
        """
        Return the next batch, each candidate with its Variant (the same until told).

        Returns:
            The candidates of the batch (core.search.optimizers.Candidate): each an id, a
            generation, a normalized genome of shape (genome_spec(batch_task).size,) with
            values in [0, 1], and the Variant of the task it is evaluated on.
        """
        if self._batch is None:
            task = self.batch_task
            horizon = self.horizon or 0.0
            candidates = self._driver.ask()
            # a hierarchy structure's check evaluates on its own number of worlds
            world_states = (self.batch_task.num_world_states
                            if self.checking and self.hierarchical else 0)
            variant = dataclasses.replace(task.variant, structure=task.structure,
                                          world_states=world_states, horizon=horizon)
            self._batch = [dataclasses.replace(candidate, variant=variant)
                           for candidate in candidates]
        return list(self._batch)

    def tell(self, results: Mapping[int, Any]) -> None:
        """
        Tell the objectives of the whole batch.

        Args:
            results: candidate id -> its objective vector (shape (objectives,): m or rad, in
                task.objective_names' order) or its core.evaluate.Evaluation, for every
                candidate of the batch of `ask()`.

        Raises:
            TellError: (core.search.optimizers) for results that miss or add candidates.
        """
        self._driver.tell(results)
        if self._horizon is not None:
            results = dict(results)
            self._horizon.told([getattr(results[c.candidate_id], 'objectives',
                                        results[c.candidate_id]) for c in self.ask()])
        self._batch = None

    def stop(self) -> Dict[str, Any]:
        """
        Return why the search ended.

        Returns:
            The termination criteria met and their values (e.g. {'maxiter': 100}); empty
            while the search goes on.
        """
        return self._driver.stop()

    @property
    def outcomes(self):
        """Return the hierarchy's StructureOutcomes so far (empty without a hierarchy)."""
        return self._driver.outcomes if self.hierarchical else []

    @property
    def best(self):
        """Return (OptimizerResult, structure) of the best design so far, or None."""
        if self.hierarchical and self._driver.result is not None:
            outcome = self._driver.result
            return outcome.result, outcome.structure
        result = self._driver.result if self.resampled else self.optimizer.result
        return None if result is None else (result, self.batch_task.structure)

    @property
    def final_check(self):
        """Return the CheckedDesigns of a resampled run's final check once told, else []."""
        return list(self._driver.checked) if self.resampled else []

    def summary_result(self, optimizer):
        """
        Return the OptimizerResult a batch's summary reports, after its tell.

        `optimizer` is the one the batch was asked from: its best so far, or for a resampled
        run once its final check is told, the check's best (the run's result).
        """
        if self.resampled and self._driver.checked:
            return self._driver.result
        return optimizer.result
