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

A resumed run's bag holds only what that run evaluated, from where the run it continued
stopped (RunInfo.resumed_from). Resuming such a bag (a run interrupted again, or continued once
more) reads the earlier runs' bags too, found beside it in the same folder; without them the
run is refused, never started over.
"""

import pathlib

from hand_codesign.analysis import records
from hand_codesign.analysis.records import recorded_evaluations
from hand_codesign.analysis.records import told_objectives
from hand_codesign.bag.reader import BagError
from hand_codesign.bag.reader import read_topics
from hand_codesign.core.contract import RUN_INFO_TYPE
from hand_codesign.core.search.resume import extended_task
from hand_codesign.core.search.resume import rebuild_search
from hand_codesign.core.search.resume import ResumePoint
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
    recorded, genomes = recorded_run(record)
    return rebuild_search(task, record.run_id, record.path, recorded, genomes, record)


def recorded_run(record):
    """
    Return (recorded evaluations, recorded genomes) of the run from its first generation.

    The bag's own, and those of the runs it continued (runs_continued), as
    recorded_evaluations and recorded_genomes give them.
    """
    recorded, genomes = {}, {}
    for part in runs_continued(record) + [record]:   # the earliest first, this run's last
        recorded.update(recorded_evaluations(part))
        genomes.update(recorded_genomes(part))
    return recorded, genomes


def runs_continued(record):
    """
    Return the RunRecords of the runs record's run continued, the earliest first.

    A fresh run's first candidate is number 0 and candidate ids go on across resumes, so a bag
    without candidate 0 whose RunInfo names resumed_from starts where that run stopped; its
    bag is looked for beside record's (UserError when it is not there).
    """
    chain = []
    while (record.run_info is not None and record.run_info.resumed_from
           and not holds_first_candidate(record)):
        record = bag_of_run(record.run_info.resumed_from, record.path)
        chain.insert(0, record)
    return chain


def holds_first_candidate(record):
    """Return whether the bag holds candidate 0, which only a run's first generation asks."""
    candidates = record.candidates
    return bool(len(candidates)) and bool(np.any(np.asarray(candidates['candidate_id']) == 0))


def bag_of_run(run_id, beside):
    """Return the RunRecord of run run_id from a bag in the folder of bag `beside`; UserError."""
    beside = pathlib.Path(beside).resolve()
    folder = beside.parent
    for entry in sorted(folder.iterdir()):
        if entry != beside and run_id in run_ids_of(entry):
            return records.open_run(entry, warn=False, run_id=run_id)
    raise UserError(f'{beside}: run {run_id}, which this run continued, holds its first '
                    f'generations, and no bag in {folder} holds it: put that bag beside this '
                    'one to resume')


def run_ids_of(path):
    """Return the run ids a bag's RunInfo messages announce (empty for anything else)."""
    named = records.result_run_id(path)
    if named:
        return {named}
    if not (path.suffix == '.mcap' or (path / 'metadata.yaml').is_file()):
        return set()
    try:
        tables, _ = read_topics(path, [RUN_INFO_TYPE])
    except BagError:
        return set()
    table = tables[RUN_INFO_TYPE]
    return set(table['run_id']) if len(table) else set()


__all__ = ['bag_of_run', 'recorded_evaluations', 'recorded_genomes', 'recorded_run',
           'resume_point', 'ResumePoint', 'runs_continued', 'told_objectives']
