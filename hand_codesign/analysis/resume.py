"""
Resuming an interrupted run from its bag: `hand-codesign run --resume BAG`.

A candidate's objectives are a pure function of (genome, task, seed), and the optimizers are
deterministic given their seed, so a run is rebuilt exactly by telling a fresh search of the
same task and seed the objectives it was told before (`core.optimizers.replay`). The recorded
objectives come from the GenerationSummary messages (`told_ids` / `told_objectives`: exactly
what the optimizer was told) and, for the batch in flight when the run stopped, from the
Evaluation messages (the first successful answer per candidate, as the optimizer takes it).
Every replayed genome is checked against the recorded Candidate messages, so a bag of another
task, seed or library version is refused instead of silently diverging.

    point = resume_point('bags/task5-...')      # ResumePoint
    point.search                                 # core.search.Search, at the interruption
    point.known                                  # id -> objectives of the pending batch known
                                                 # from the bag: do not evaluate those again

The optimizer node continues from `point.search` as from a fresh one; candidate ids continue
where the interrupted run stopped, and the final result equals an uninterrupted run's.
"""

import dataclasses

from hand_codesign.analysis import records
from hand_codesign.analysis.records import recorded_evaluations
from hand_codesign.analysis.records import told_objectives
from hand_codesign.core.optimizers import replay
from hand_codesign.core.optimizers import ReplayError
from hand_codesign.core.optimizers import TellError
from hand_codesign.core.search import Search
from hand_codesign.errors import UserError
import numpy as np


def recorded_genomes(record):
    """Return {candidate id: normalized genome} of the Candidate messages (first dispatch)."""
    candidates = record.candidates
    genomes = {}
    if not len(candidates):
        return genomes
    for index, candidate_id in enumerate(np.asarray(candidates['candidate_id']).tolist()):
        if candidate_id not in genomes:
            genomes[int(candidate_id)] = np.asarray(candidates['genome'][index], dtype=float)
    return genomes


@dataclasses.dataclass
class ResumePoint:
    """A run's search rebuilt up to where its bag ends."""

    record: object               # the RunRecord of the interrupted run
    run_id: str                  # the interrupted run's id (RunInfo.resumed_from of the new)
    task: object                 # the run's Task
    search: Search               # at the interruption: ask() gives the batch to continue with
    batches_told: int
    evaluations_told: int
    known: dict                  # id -> objectives of the pending batch already in the bag
    recorded: dict               # id -> objectives of everything in the bag

    @property
    def pending(self):
        """Return the batch to continue with (candidates), empty if the search has stopped."""
        return [] if self.search.stop() else self.search.ask()

    @property
    def to_evaluate(self):
        """Return the pending candidates whose objectives the bag does not hold."""
        return [candidate for candidate in self.pending
                if candidate.candidate_id not in self.known]

    def describe(self):
        """Return a one-line account of what was recovered."""
        return (f'resuming run {self.run_id} of task {self.task.name} (seed {self.task.seed}): '
                f'{self.batches_told} batches ({self.evaluations_told} evaluations) replayed '
                f'from the bag, {len(self.known)} evaluations of the next batch recovered, '
                f'{len(self.to_evaluate)} to evaluate next')


def resume_point(bag_or_record):
    """
    Return the ResumePoint of an interrupted run (a bag path or a RunRecord).

    Raise UserError when the bag cannot be read, has no RunInfo, disagrees with the replayed
    search (other task, seed or library versions), or holds a run that already finished.
    """
    record = (records.open_run(bag_or_record) if isinstance(bag_or_record, (str, bytes))
              or hasattr(bag_or_record, '__fspath__') else bag_or_record)
    task = records.run_task_of(record)
    search = Search(task)
    recorded = recorded_evaluations(record)
    try:
        batches = replay(search, recorded, recorded_genomes(record))
    except (ReplayError, TellError) as error:
        raise UserError(f'{record.path}: cannot resume: the recorded run disagrees with a '
                        f'fresh search of its task and seed: {error}') from None
    if search.stop():
        best = search.best
        raise UserError(
            f'{record.path}: run {record.run_id} already finished '
            f'({", ".join(f"{key}={value}" for key, value in search.stop().items())}); '
            'nothing to resume' + (f'; its best design is candidate {best[0].candidate_id}'
                                   if best else ''))
    pending = search.ask()
    known = {c.candidate_id: recorded[c.candidate_id] for c in pending
             if c.candidate_id in recorded}
    told = sum(1 for candidate_id in recorded if candidate_id not in known)
    return ResumePoint(record=record, run_id=record.run_id, task=task, search=search,
                       batches_told=batches, evaluations_told=told, known=known,
                       recorded=recorded)


__all__ = ['recorded_evaluations', 'recorded_genomes', 'resume_point', 'ResumePoint',
           'told_objectives']
