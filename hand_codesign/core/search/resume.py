"""
Rebuilding a run's search from its recorded evaluations, to continue an interrupted run.

A candidate's objectives are a pure function of (genome, task, seed), and the optimizers are
deterministic given their seed, so a run is rebuilt exactly by telling a fresh search of the
same task and seed the objectives it was told before (`core.search.optimizers.replay`). Every
replayed genome is checked against the recorded one, so a record of another task, seed or
library version is refused instead of silently diverging.

Where the recorded evaluations come from (a bag) is not this module's concern:
`hand_codesign.analysis.resume.resume_point(bag)` reads them and calls `rebuild_search`.

    point = rebuild_search(task, run_id, source, recorded, genomes)   # ResumePoint
    point.search      # core.search.search.Search, at the interruption
    point.known       # id -> objectives of the pending batch already recorded: do not
                      # evaluate those again

A finished run of one optimizer continues for more generations with the same replay:
`extended_task(task, iterations, source)` is its task with the larger budget. The optimizers
sample the same candidates whatever their generation budget (it only ends a run), so the
replayed generations are the recorded ones and the run goes on as one that had the larger
budget from its start.
"""

import dataclasses

from hand_codesign.arithmetic import NATIVE
from hand_codesign.core.search.optimizers import replay
from hand_codesign.core.search.optimizers import ReplayError
from hand_codesign.core.search.optimizers import TellError
from hand_codesign.core.search.search import Search
from hand_codesign.core.task.parts import RESTART_ALGORITHMS
from hand_codesign.errors import UserError


@dataclasses.dataclass
class ResumePoint:
    """A run's search rebuilt up to where its record ends."""

    record: object               # where the evaluations came from (e.g. the bag's RunRecord)
    run_id: str                  # the interrupted run's id (RunInfo.resumed_from of the new)
    task: object                 # the run's Task
    search: Search               # at the interruption: ask() gives the batch to continue with
    batches_told: int
    evaluations_told: int
    known: dict                  # id -> objectives of the pending batch already recorded
    recorded: dict               # id -> objectives of everything recorded

    @property
    def pending(self):
        """Return the batch to continue with (candidates), empty if the search has stopped."""
        return [] if self.search.stop() else self.search.ask()

    @property
    def to_evaluate(self):
        """Return the pending candidates whose objectives the record does not hold."""
        return [candidate for candidate in self.pending
                if candidate.candidate_id not in self.known]

    def describe(self):
        """Return a one-line account of what was recovered."""
        return (f'resuming run {self.run_id} of task {self.task.name} (seed {self.task.seed}, '
                f'{self.task.iterations} generations): '
                f'{self.batches_told} batches ({self.evaluations_told} evaluations) replayed '
                f'from the bag, {len(self.known)} evaluations of the next batch recovered, '
                f'{len(self.to_evaluate)} to evaluate next')


def extended_task(task, iterations, source):
    """
    Return task with `iterations` generations, more than its own, to continue a run of it.

    Raise UserError (naming `source`, the run's record) for a budget that is not larger, or for
    a search whose later batches depend on where it ends: a hierarchy (each structure's
    generations), a two-stage task (stage 2 starts after stage 1's last generation),
    resampled worlds (a final check follows the last generation) and restarts (the budget
    cuts the last generation and bounds an instance).
    """
    if iterations <= task.iterations:
        raise UserError(f'--iterations {iterations}: a resumed run continues to more '
                        f'generations than the {task.iterations} of {source}')
    kind = ('a structure hierarchy' if task.hierarchy is not None
            else 'two stages' if task.two_stage
            else 'worlds resampled each generation' if task.worlds.resample == 'generation'
            else f'with restarts ({task.algorithm})' if task.algorithm in RESTART_ALGORITHMS
            else None)
    if kind:
        raise UserError(f'--iterations with --resume: {source} searches {kind}, whose later '
                        'batches depend on its budget; only a run of one optimizer continues '
                        'for more generations')
    return task.replace(iterations=int(iterations))


def rebuild_search(task, run_id, source, recorded, genomes, record=None):
    """
    Return the ResumePoint of run run_id of task from its recorded evaluations.

    recorded: id -> objectives as the optimizer was told them, or a racing run's
    core.search.racing.RacedAnswer (and, for the batch in flight, the first successful answer,
    which a raced run does not take); genomes: id -> genome as first dispatched; source names the
    record in messages. Raise UserError when the record disagrees with the replayed search or
    holds a run that already finished.
    """
    search = Search(task)
    try:
        batches = replay(search, recorded, genomes)
    except (ReplayError, TellError) as error:
        raise UserError(f'{source}: cannot resume: the recorded run disagrees with a '
                        f'fresh search of its task and seed: {error} (a run recorded on a '
                        'processor with AVX-512 before the arithmetic was pinned resumes with '
                        f'{NATIVE}=1 on a processor of that kind)') from None
    if search.stop():
        best = search.best
        raise UserError(
            f'{source}: run {run_id} already finished '
            f'({", ".join(f"{key}={value}" for key, value in search.stop().items())}); '
            'nothing to resume' + (f'; its best design is candidate {best[0].candidate_id}'
                                   if best else ''))
    pending = search.ask()
    if task.worlds.racing is not None:
        # a raced batch's Evaluations answer rounds, not candidates (core.run.rounds): the
        # batch in flight races again from its first round, to the same results
        pending_ids = {c.candidate_id for c in pending}
        recorded = {key: value for key, value in recorded.items() if key not in pending_ids}
    known = {c.candidate_id: recorded[c.candidate_id] for c in pending
             if c.candidate_id in recorded}
    told = sum(1 for candidate_id in recorded if candidate_id not in known)
    return ResumePoint(record=record, run_id=run_id, task=task, search=search,
                       batches_told=batches, evaluations_told=told, known=known,
                       recorded=recorded)
