"""
Resuming an interrupted run from its bag: `hand-codesign run --resume BAG`.

This module only reads the bag; `core.search.resume.rebuild_search` rebuilds the search from what
it read (a fresh search of the run's task and seed told the recorded objectives). The recorded
objectives come from the GenerationSummary messages (`told_ids` / `told_objectives`: exactly
what the optimizer was told) and, for the batch in flight when the run stopped, from the
Evaluation messages (the first successful answer per candidate, as the optimizer takes it).
Every replayed genome is checked against the recorded Candidate messages.

    point = resume_point('bags/task5-...')      # ResumePoint
    point.search                                 # core.search.search.Search, at the interruption
    point.known                                  # id -> objectives of the pending batch known
                                                 # from the bag: do not evaluate those again
    resume_point('bags/task5-...', iterations=200)   # a finished run of 100 generations, on
                                                 # to 200

The optimizer node continues from `point.search` as from a fresh one; candidate ids continue
where the interrupted run stopped, and the final result equals an uninterrupted run's.
"""

from hand_codesign.analysis import records
from hand_codesign.analysis.records import recorded_evaluations
from hand_codesign.analysis.records import told_objectives
from hand_codesign.core.search.resume import extended_task
from hand_codesign.core.search.resume import rebuild_search
from hand_codesign.core.search.resume import ResumePoint
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


def resume_point(bag_or_record, iterations=0):
    """
    Return the ResumePoint of an interrupted run (a bag path or a RunRecord).

    `iterations` > 0 continues the run to that many generations, more than its own
    (core.search.resume.extended_task): a finished run goes on. Raise UserError when the bag
    cannot be read, has no RunInfo, disagrees with the replayed search (other task, seed or
    library versions), or holds a run that already finished.
    """
    record = (records.open_run(bag_or_record) if isinstance(bag_or_record, (str, bytes))
              or hasattr(bag_or_record, '__fspath__') else bag_or_record)
    task = records.run_task_of(record)
    if iterations:
        task = extended_task(task, iterations, record.path)
    return rebuild_search(task, record.run_id, record.path, recorded_evaluations(record),
                          recorded_genomes(record), record)


__all__ = ['recorded_evaluations', 'recorded_genomes', 'resume_point', 'ResumePoint',
           'told_objectives']
