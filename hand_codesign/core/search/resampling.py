"""
Worlds resampled each generation (`worlds: {resample: generation}`), and the final check.

Why: on one fixed set of worlds the search fits that set; Task 5's design scored 4.4 mm on its
8 training worlds and 7.9 mm on unseen ones. Here generation g of the optimizer evaluates every
candidate on draw k = g + 1 (core.sim.worlds: `world_states` fresh worlds from the stream
[seed, RESAMPLE_STREAM, k], apart from the fixed, held-out and unseen worlds), so no design is
ranked on worlds it was selected on twice, at the same rollout budget. Each candidate carries
its draw (Candidate.world_draw), so any evaluator, replay, resume and audit rebuild its worlds.

Which design the run reports: with a fresh draw per generation, the lowest weighted sum ever
told (what the optimizer's `result` holds) is biased towards a generation whose draw happened
to be easy, or a candidate lucky on its draw. So when the optimizer stops, the run takes the
best candidate of each of the last `worlds.final_check` generations (the lowest weighted sum on
its own draw, the first on ties) and evaluates them once more, as one batch, on the run's fixed
worlds (world_draw 0: the training worlds of a run without resampling, which this run never
trained on). The one of lowest weighted sum there (the earlier generation on ties) is the
run's result: its check candidate id is the final summary's best id, its objectives those on
the fixed worlds. The fixed worlds rather than the hierarchy's held-out ones, so the result's
score compares with that of a run without resampling on the same worlds, and the held-out and
unseen worlds stay untouched for the measures of robustness. The last generations rather than
all: CMA-ES converges, so their bests are the candidates worth it, at a cost of `final_check`
evaluations (default 5; fewer when the run has fewer generations).

Both choices (a generation's best, the check's best) are by the weighted sum of the task's
weights, also under MO-CMA-ES: a Pareto front of objectives measured on different draws
would not compare either, so its point closest to zero is not the rule here.

The check is a function of the objectives told, so replaying them (resume, analysis) re-derives
it; `Search.checking` is true for its batch, whose summary has check = true.
"""

import dataclasses

from hand_codesign.core.search.factory import make_optimizer
from hand_codesign.core.search.optimizers import Candidate, OptimizerResult, TellError
from hand_codesign.core.task.genome import genome_spec
import numpy as np


@dataclasses.dataclass(frozen=True)
class CheckedDesign:
    """One generation's best design re-evaluated on the fixed worlds by the final check."""

    check_id: int  # candidate id of its check evaluation
    candidate_id: int  # the candidate it repeats (evaluated on its generation's draw)
    generation: int
    draw_fitness: float  # weighted sum on its generation's draw
    objectives: np.ndarray  # on the fixed worlds
    fitness: float


class ResampledSearch:
    """One optimization on a fresh draw of worlds per generation, then the final check."""

    def __init__(self, task, first_id=0):
        self.task = task
        self._optimizer = make_optimizer(task, genome_spec(task).size, first_id=first_id)
        self._tasks = {}  # world draw -> task
        self._bests = []  # per generation told: (its best Candidate, weighted sum on its draw)
        self._check = None  # the final check's candidates while it is asked
        self._origins = []  # the (Candidate, draw fitness) each check candidate repeats
        self.checked = []  # CheckedDesign of each check candidate, once told
        self._result = None

    @property
    def optimizer(self):
        """Return the run's optimizer."""
        return self._optimizer

    @property
    def checking(self):
        """Return True while the batch asked is the final check."""
        return self._check is not None

    @property
    def evaluation_task(self):
        """Return the task of the batch asked: the generation's draw, or the fixed worlds."""
        draw = 0 if self._check is not None or self._result is not None \
            else self._optimizer.generation + 1
        if draw not in self._tasks:
            self._tasks[draw] = self.task.replace(world_draw=draw) if draw else self.task
        return self._tasks[draw]

    def ask(self):
        """Return the generation's candidates, or the final check's (the same until told)."""
        if self._result is not None:
            return []
        if self._check is not None:
            return list(self._check)
        return self._optimizer.ask()

    def tell(self, results):
        """Tell the objectives (id -> vector or Evaluation) of the batch asked."""
        if self._result is not None:
            raise TellError('the resampled search has finished its final check; nothing to '
                            'tell')
        if self._check is not None:
            self._tell_check(results)
            return
        candidates = self._optimizer.ask()
        told = dict(results)
        self._optimizer.tell(told)
        fitness = [self._optimizer.fitness_of(_vector(told[c.candidate_id]))
                   for c in candidates]
        best = int(np.argmin(fitness))  # the first on ties
        self._bests.append((candidates[best], fitness[best]))
        if self._optimizer.stop():
            self._ask_check()

    def stop(self):
        """Return why the search stopped (after the final check), as a dict; empty before."""
        if self._result is None:
            return {}
        return {**self._optimizer.stop(), 'final_check': len(self.checked)}

    @property
    def result(self):
        """Return the final check's best as an OptimizerResult; before it, the optimizer's."""
        return self._result if self._result is not None else self._optimizer.result

    @property
    def next_id(self):
        """Return the id the next new candidate will get."""
        if self._check is not None:
            return self._check[-1].candidate_id + 1
        return self._optimizer.next_id

    def _ask_check(self):
        self._origins = self._bests[-self.task.worlds.final_check:]
        first, generation = self._optimizer.next_id, self._optimizer.generation
        self._check = [Candidate(first + index, generation, candidate.x)
                       for index, (candidate, _) in enumerate(self._origins)]

    def _tell_check(self, results):
        told = {int(key): value for key, value in dict(results).items()}
        asked = [c.candidate_id for c in self._check]
        if sorted(told) != asked:
            raise TellError(f'tell() refused: the final check expects ids {asked}, got ids '
                            f'{sorted(told)}', missing=set(asked) - set(told),
                            unknown=set(told) - set(asked))
        checked = []
        for candidate, (origin, draw_fitness) in zip(self._check, self._origins):
            objectives = _vector(told[candidate.candidate_id])
            if objectives.shape != (self._optimizer.num_objectives,) or \
                    not np.all(np.isfinite(objectives)):
                raise TellError(f'tell() refused: id {candidate.candidate_id} needs '
                                f'{self._optimizer.num_objectives} finite objective values',
                                invalid=[candidate.candidate_id])
            checked.append(CheckedDesign(candidate.candidate_id, origin.candidate_id,
                                         origin.generation, draw_fitness, objectives,
                                         self._optimizer.fitness_of(objectives)))
        winner = min(range(len(checked)), key=lambda index: checked[index].fitness)
        best, candidate = checked[winner], self._check[winner]
        optimizer = self._optimizer
        self._result = OptimizerResult(
            best.check_id, candidate.generation, candidate.x, best.objectives, best.fitness,
            optimizer.evaluations + len(checked), optimizer.generation)
        self.checked = checked
        self._check = None


def _vector(values):
    return np.asarray(getattr(values, 'objectives', values), dtype=float).reshape(-1)
