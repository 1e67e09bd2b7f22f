"""
What the analysis verbs need from a run's bag: its task, its evaluations and its designs.

`open_run(path)` reads a bag with `bag.read_run`, turning a BagError into the CLI's UserError
and printing the reader's warnings (a truncated bag is read up to the cut). The other functions
work on the RunRecord it returns:

- `run_task_of(record, variant)`: the Task of the run (as every process of the run rebuilt it,
  `core.run.runs.run_task`), or the version of it a candidate's Variant says, if asked;
- `evaluation_rows(record)`: every Evaluation joined with its Candidate (genome, structure),
  with a status of 'ok', 'rejected', 'duplicate' (a later answer for an already evaluated
  candidate, which the optimizer ignored, or an audit's), 'untold' (an answer that differs
  from what the summaries say was told: a forgery the optimizer ignored, or a liar's) or
  'round' (the first answer to a racing round's share of a candidate's worlds,
  core.search.racing: the summaries hold what the rounds added up to);
- `recorded_design(record, candidate_id)`: one recorded candidate with its recorded result;
- `best_candidate_id(record)` and `ranked_candidate_id(record, generation, rank)`: which design
  a verb works on by default and on request;
- `restarts_of(record)`: the CMA-ES instances of a run with restarts (ipop-cma, bipop-cma);
- `archive_of(record)`: the quality-diversity optimizer (cma-mae, cma-me) with its archive;
- `stepping_rate(record)`: the physics steps per wall second of the run, as its user saw it.
"""

import collections
import dataclasses
import json
import pathlib
import sys

from hand_codesign.bag.reader import BagError
from hand_codesign.bag.reader import read_run
from hand_codesign.core.contract import STATUS_NAMES
from hand_codesign.core.contract import STATUS_OK
from hand_codesign.core.outcomes import Answer
from hand_codesign.core.outcomes import objectives_of
from hand_codesign.core.search.optimizers import OptimizerError
from hand_codesign.core.search.optimizers import replay
from hand_codesign.core.search.racing import RacedAnswer
from hand_codesign.core.search.search import Search
from hand_codesign.core.sim.objectives import weighted_fitness
from hand_codesign.core.task import TaskError
from hand_codesign.core.task.parts import QD_ALGORITHMS
from hand_codesign.core.task.parts import RESTART_ALGORITHMS
from hand_codesign.core.task.variant import Variant
from hand_codesign.errors import UserError
import numpy as np


def beside_bag(bag_path, suffix):
    """Return the path `<bag name><suffix>` next to the bag (a folder or an .mcap file)."""
    path = pathlib.Path(bag_path).resolve()
    stem = path.stem if path.is_file() else path.name
    return path.parent / f'{stem}{suffix}'


def result_run_id(path):
    """
    Return the run id of the result.json in a bag folder, or None.

    The optimizer of the run wrote it; anything on the run's domain can put a RunInfo of
    another run into the bag, and the bag holds no key to tell which is the run's own.
    """
    result = pathlib.Path(path) / 'result.json'
    try:
        return json.loads(result.read_text()).get('run_id') if result.is_file() else None
    except (OSError, ValueError, AttributeError):
        return None


def open_run(path, warn=True, run_id=None):
    """Return the RunRecord of run_id, else of the bag's result.json run, if any; UserError."""
    try:
        try:
            record = read_run(path, run_id=run_id or result_run_id(path))
        except BagError:
            if run_id:
                raise
            record = read_run(path)
    except BagError as error:
        raise UserError(str(error)) from None
    if warn:
        for warning in record.warnings:
            print(f'warning: {warning}', file=sys.stderr)
    return record


def require_run_info(record, purpose):
    """Return the record's RunInfo, or raise UserError saying why `purpose` needs it."""
    if record.run_info is None:
        raise UserError(f'{record.path}: the bag holds no RunInfo message of run '
                        f'{record.run_id!r}, so its task and seed are unknown; {purpose} '
                        'needs them')
    return record.run_info


def run_task_of(record, variant=None):
    """Return the Task of the run (the version `variant`, a core.task.variant.Variant, of it)."""
    info = require_run_info(record, 'rebuilding the task')
    try:
        return info.task(variant, f'{record.path} (RunInfo.task_yaml)')
    except (TaskError, ValueError) as error:
        raise UserError(f'{record.path}: the task recorded in the bag cannot be rebuilt: '
                        f'{error}') from None


def objective_names_of(record):
    """Return the run's objective names (RunInfo, else the first evaluation's)."""
    if record.run_info is not None and record.run_info.objective_names:
        return list(record.run_info.objective_names)
    evaluations = record.evaluations
    if len(evaluations) and 'objective_names' in evaluations:
        for names in evaluations['objective_names']:
            if names:
                return list(names)
    summaries = record.generation_summaries
    if len(summaries) and 'objective_names' in summaries:
        return list(summaries['objective_names'][0])
    return []


def _first_index(ids):
    """Return {id: index of its first occurrence} as (sorted unique ids, first indices)."""
    unique, first = np.unique(np.asarray(ids, dtype=np.uint64), return_index=True)
    return unique, first


def _lookup(unique, first, ids):
    """Return the first-occurrence row of each id in ids, -1 where it is unknown."""
    ids = np.asarray(ids, dtype=np.uint64)
    if not len(unique):
        return np.full(len(ids), -1, dtype=np.int64)
    position = np.searchsorted(unique, ids)
    position = np.minimum(position, len(unique) - 1)
    found = unique[position] == ids
    return np.where(found, first[position], -1).astype(np.int64)


def _row_matrix(column, rows, width):
    """Return rows of a numeric list column as a (len(rows), width) float array, NaN-padded."""
    out = np.full((len(rows), width), np.nan)
    if not len(rows) or width == 0:
        return out
    if isinstance(column, np.ndarray) and column.dtype != object and column.ndim == 2:
        valid = rows >= 0
        values = column[rows[valid]]
        out[valid, :values.shape[1]] = values[:, :width]
        return out
    for index, row in enumerate(rows):
        if row >= 0:
            value = np.asarray(column[row], dtype=float)
            count = min(len(value), width)
            out[index, :count] = value[:count]
    return out


@dataclasses.dataclass
class EvaluationRows:
    """Every Evaluation message of a run, in recorded order, with its candidate's genome."""

    objective_names: list
    generation: np.ndarray
    candidate_id: np.ndarray
    evaluator_id: np.ndarray     # object array of str
    status: np.ndarray           # object array: 'ok', 'rejected', 'duplicate' or 'untold'
    reason: np.ndarray           # object array of str
    objectives: np.ndarray       # (rows, objectives), NaN for rejections
    fitness: np.ndarray
    collision: np.ndarray
    unstable_worlds: np.ndarray
    simulated_time: np.ndarray
    wall_time: np.ndarray
    log_time: np.ndarray         # ns, when the recorder received it
    candidate_row: np.ndarray    # row of the candidates table, -1 when not recorded
    gene_names: list             # union of the gene names of every structure, first seen first
    genes: np.ndarray            # (rows, len(gene_names)), NaN where a gene does not apply

    def __len__(self):
        """Return the number of evaluations."""
        return len(self.candidate_id)

    @property
    def ok(self):
        """Return the mask of the evaluations the optimizer used."""
        return self.status == 'ok'


def _statuses(evaluations):
    """Return the status names; a later OK answer for an answered candidate is a duplicate."""
    status_codes = np.asarray(evaluations['status'], dtype=np.int64)
    names = np.array([STATUS_NAMES.get(int(code), f'status {int(code)}')
                      for code in range(status_codes.max(initial=0) + 1)], dtype=object)
    statuses = names[status_codes] if len(status_codes) else np.array([], dtype=object)
    ok_rows = np.flatnonzero(status_codes == STATUS_OK)
    ids = np.asarray(evaluations['candidate_id'], dtype=np.uint64)[ok_rows]
    _, first = np.unique(ids, return_index=True)
    repeated = np.ones(len(ok_rows), dtype=bool)
    repeated[first] = False
    statuses[ok_rows[repeated]] = 'duplicate'
    return statuses


def _told_statuses(statuses, evaluations, objectives, told):
    """
    Return statuses with the summaries' word on what was told.

    For a candidate the summaries hold, the first OK answer equal to the told objectives bit
    for bit is 'ok', later equal ones 'duplicate', different ones 'untold'.
    """
    if not told or not objectives.shape[1]:
        return statuses
    told_ids = np.array(sorted(told), dtype=np.uint64)
    told_values = np.array([told[int(i)] for i in told_ids], dtype=float)
    rows = np.flatnonzero(np.isin(statuses, ('ok', 'duplicate')))
    ids = np.asarray(evaluations['candidate_id'], dtype=np.uint64)[rows]
    position = np.minimum(np.searchsorted(told_ids, ids), len(told_ids) - 1)
    known = told_ids[position] == ids
    rows, ids, position = rows[known], ids[known], position[known]
    same = np.all(objectives[rows].view(np.uint64)
                  == told_values[position].view(np.uint64), axis=1)   # bit for bit
    statuses = statuses.copy()
    statuses[rows[~same]] = 'untold'
    statuses[rows[same]] = 'duplicate'
    _, first = np.unique(ids[same], return_index=True)
    statuses[rows[same][first]] = 'ok'
    return statuses


def round_shares(record):
    """Return {(candidate id, attempt): (first, end)} of the racing rounds a run sent."""
    candidates = record.candidates
    if not len(candidates) or 'worlds_to' not in candidates:
        return {}
    return {(int(candidate_id), int(attempt)): (int(first), int(end))
            for candidate_id, attempt, first, end in zip(
                candidates['candidate_id'], candidates['attempt'], candidates['worlds_from'],
                candidates['worlds_to']) if end == end and int(end) > 0}


def _round_statuses(statuses, evaluations, shares):
    """Return statuses with each racing round's first answer 'round', later ones 'duplicate'."""
    if not shares:
        return statuses
    statuses, seen = statuses.copy(), set()
    for row, (candidate_id, attempt) in enumerate(zip(evaluations['candidate_id'],
                                                      evaluations['attempt'])):
        share = shares.get((int(candidate_id), int(attempt)))
        if share is None or statuses[row] == 'rejected':
            continue
        key = (int(candidate_id), share)
        statuses[row] = 'duplicate' if key in seen else 'round'
        seen.add(key)
    return statuses


def _genes(candidates, rows):
    """Return (gene names, (len(rows), genes) physical-free genome matrix) of candidate rows."""
    if not len(candidates) or 'genome' not in candidates:
        return [], np.full((len(rows), 0), np.nan)
    name_column = candidates['genome_names']
    genome_column = candidates['genome']
    valid = rows >= 0
    groups = {}
    for index in np.flatnonzero(valid):
        groups.setdefault(name_column[rows[index]], []).append(index)
    gene_names = list(dict.fromkeys(name for names in groups for name in names))
    position = {name: index for index, name in enumerate(gene_names)}
    genes = np.full((len(rows), len(gene_names)), np.nan)
    for names, members in groups.items():
        members = np.array(members)
        columns = np.array([position[name] for name in names], dtype=np.int64)
        values = _row_matrix(genome_column, rows[members], len(names))
        genes[members[:, None], columns[None, :]] = values
    return gene_names, genes


def evaluation_rows(record):
    """Return the EvaluationRows of a RunRecord."""
    evaluations = record.evaluations
    names = objective_names_of(record)
    count = len(evaluations)
    if not count:
        empty = np.array([], dtype=float)
        return EvaluationRows(names, empty, empty, empty, empty, empty,
                              np.full((0, len(names)), np.nan), empty, empty, empty, empty,
                              empty, empty, np.array([], dtype=np.int64), [],
                              np.full((0, 0), np.nan))
    unique, first = _first_index(record.candidates['candidate_id']) if len(
        record.candidates) else (np.array([], dtype=np.uint64), np.array([], dtype=np.int64))
    candidate_row = _lookup(unique, first, evaluations['candidate_id'])
    gene_names, genes = _genes(record.candidates, candidate_row)
    objectives = _row_matrix(evaluations['objectives'], np.arange(count), len(names))
    return EvaluationRows(
        objective_names=names,
        generation=np.asarray(evaluations['generation'], dtype=np.int64),
        candidate_id=np.asarray(evaluations['candidate_id'], dtype=np.uint64),
        evaluator_id=np.asarray(evaluations['evaluator_id'], dtype=object),
        status=_round_statuses(_told_statuses(_statuses(evaluations), evaluations, objectives,
                                              told_objectives(record)),
                               evaluations, round_shares(record)),
        reason=np.asarray(evaluations['reason'], dtype=object),
        objectives=objectives,
        fitness=np.asarray(evaluations['fitness'], dtype=float),
        collision=np.asarray(evaluations['collision'], dtype=bool),
        unstable_worlds=np.asarray(evaluations['unstable_worlds'], dtype=np.int64),
        simulated_time=np.asarray(evaluations['simulated_time'], dtype=float),
        wall_time=np.asarray(evaluations['wall_time'], dtype=float),
        log_time=np.asarray(evaluations['log_time'], dtype=np.int64),
        candidate_row=candidate_row,
        gene_names=gene_names,
        genes=genes,
    )


def stepping_rate(record):
    """
    Return the physics steps per wall second of a run, from its bag.

    The steps of the accepted evaluations (simulated_time over the time step, once per
    candidate, or per racing round of it: audits and late duplicates are cost, not progress),
    over the wall time from the first candidate recorded to the last evaluation.
    """
    rows = evaluation_rows(record)
    used = np.isin(rows.status, ('ok', 'round'))
    steps = np.sum(rows.simulated_time[used]) / run_task_of(record).time_step
    return steps / ((np.max(rows.log_time) - np.min(record.candidates['log_time'])) * 1e-9)


@dataclasses.dataclass
class RecordedDesign:
    """One recorded candidate: its genome and the result the run recorded for it."""

    candidate_id: int
    generation: int
    structure: tuple
    world_states: int            # 0: the run's number of world states
    horizon: float               # s, its sub-problem (search.horizon); 0: none (older bags too)
    x: np.ndarray                # normalized genome, as sent to the evaluator
    genome_names: tuple
    objective_names: list
    objectives: np.ndarray       # None when the bag holds no OK evaluation of it
    fitness: float
    world_objectives: np.ndarray  # (worlds, objectives), or None
    evaluator_id: str
    stage: int = 0               # of a two-stage task (search.stages); 0: one stage, older bags
    held_out: bool = False       # evaluated on the held-out worlds (a hierarchy check)
    world_draw: int = 0          # its resampled worlds (Candidate.world_draw); 0: the fixed ones

    @property
    def variant(self):
        """Return the Variant of the run's task it was evaluated on (its Candidate's fields)."""
        return Variant(structure=tuple(self.structure), world_states=int(self.world_states),
                       horizon=float(self.horizon), stage=int(self.stage),
                       held_out=bool(self.held_out), world_draw=int(self.world_draw))


def recorded_design(record, candidate_id):
    """Return the RecordedDesign of candidate_id, or raise UserError when it is not recorded."""
    candidates = record.candidates
    ids = np.asarray(candidates['candidate_id'], dtype=np.uint64) if len(candidates) else []
    rows = np.flatnonzero(np.asarray(ids) == np.uint64(candidate_id))
    if not len(rows):
        raise UserError(f'{record.path}: candidate {candidate_id} is not in the bag (no '
                        'Candidate message with its genome)')
    candidate = candidates.row(int(rows[0]))
    names = objective_names_of(record)
    objectives = fitness = world_objectives = None
    evaluator_id = ''
    evaluations = record.evaluations
    if len(evaluations):
        matches = np.flatnonzero(
            (np.asarray(evaluations['candidate_id'], dtype=np.uint64) == np.uint64(candidate_id))
            & (np.asarray(evaluations['status']) == STATUS_OK))
        told = told_objectives(record).get(int(candidate_id))
        if told is not None:  # rather the answer told than a forgery or a liar's
            same = [row for row in matches if np.asarray(
                evaluations['objectives'][row], dtype=float).tobytes() == told.tobytes()]
            matches = same or matches
        raced = _raced_result(record, candidate_id, matches, told)
        if raced is not None:
            objectives, fitness, world_objectives, evaluator_id = raced
        elif len(matches):
            evaluation = evaluations.row(int(matches[0]))
            objectives = np.asarray(evaluation['objectives'], dtype=float)
            fitness = float(evaluation['fitness'])
            world = np.asarray(evaluation['world_objectives'], dtype=float)
            world_objectives = world.reshape(-1, len(objectives)) if len(objectives) else None
            evaluator_id = str(evaluation['evaluator_id'])
    return RecordedDesign(
        candidate_id=int(candidate_id), generation=int(candidate['generation']),
        structure=tuple(int(joints) for joints in candidate['structure']),
        world_states=int(candidate.get('world_states', 0) or 0),
        horizon=float(candidate.get('horizon', 0.0) or 0.0),
        stage=int(candidate.get('stage', 0) or 0),
        held_out=bool(candidate.get('held_out_worlds', False)),
        world_draw=int(candidate.get('world_draw', 0) or 0),
        x=np.asarray(candidate['genome'], dtype=float),
        genome_names=tuple(candidate['genome_names']), objective_names=names,
        objectives=objectives, fitness=fitness, world_objectives=world_objectives,
        evaluator_id=evaluator_id)


def _raced_result(record, candidate_id, rows, told):
    """
    Return (objectives, fitness, world objectives, evaluator) of a raced candidate, or None.

    Its Evaluations answer racing rounds (core.search.racing): its result is what the
    summaries say was told, over the worlds of its rounds' first answers, in world order.
    """
    shares = round_shares(record)
    evaluations = record.evaluations
    parts = {}
    for row in rows:
        share = shares.get((int(candidate_id), int(evaluations['attempt'][row])))
        if share is not None:
            parts.setdefault(share, row)
    if told is None or not parts:
        return None
    worlds = [np.asarray(evaluations['world_objectives'][parts[share]], dtype=float)
              for share in sorted(parts)]
    fitness = weighted_fitness(told, run_task_of(record).objective_weights)
    evaluators = sorted({str(evaluations['evaluator_id'][row]) for row in parts.values()})
    return (told.copy(), fitness, np.concatenate(worlds).reshape(-1, len(told)),
            ', '.join(evaluators))


def design_task(record, design):
    """Return the Task with which a RecordedDesign was evaluated."""
    return run_task_of(record, design.variant)


def last_summary(record):
    """Return the last GenerationSummary row (a dict), or None."""
    summaries = record.generation_summaries
    if not len(summaries):
        return None
    return summaries.row(len(summaries) - 1)


def told_objectives(record):
    """Return {candidate id: objectives} as told to the optimizer, from the summaries."""
    summaries = record.generation_summaries
    told = {}
    if not len(summaries) or 'told_ids' not in summaries:
        return told
    count = len(objective_names_of(record))
    for index in range(len(summaries)):
        ids = np.asarray(summaries['told_ids'][index]).ravel()
        if ids.dtype.kind == 'f':   # the table pads the empty lists of some rows with NaN
            ids = ids[np.isfinite(ids)]
        ids = ids.astype(np.uint64)
        if not len(ids) or not count:
            continue
        values = np.asarray(summaries['told_objectives'][index], dtype=float).ravel()
        values = values[:len(ids) * count].reshape(len(ids), count)
        for candidate_id, objectives in zip(ids.tolist(), values):
            told.setdefault(int(candidate_id), objectives.copy())
    return told


def told_worlds(record):
    """
    Return {candidate id: (worlds met, the batch's worlds)} of a raced run's summaries.

    Racing (core.search.racing) records per told candidate the worlds it met (told_worlds);
    at least mu candidates of a batch meet all of them, so the most any met is the batch's.
    Empty for a run without racing (and bags older than the field).
    """
    summaries = record.generation_summaries
    met = {}
    if not len(summaries) or 'told_worlds' not in summaries:
        return met
    for index in range(len(summaries)):
        worlds = np.asarray(summaries['told_worlds'][index]).ravel()
        ids = np.asarray(summaries['told_ids'][index]).ravel()
        if worlds.dtype.kind == 'f':   # the table pads the empty lists of some rows with NaN
            worlds, ids = worlds[np.isfinite(worlds)], ids[np.isfinite(ids)]
        if not len(worlds) or len(worlds) != len(ids):
            continue
        most = int(worlds.max())
        for candidate_id, count in zip(ids.astype(np.uint64).tolist(), worlds.tolist()):
            met.setdefault(int(candidate_id), (int(count), most))
    return met


def raced_rollouts(met):
    """
    Return (rollouts run, rollouts a full run would have run, candidates stopped early).

    met: told_worlds(record), {candidate id: (worlds met, the batch's worlds)}.
    """
    ran = sum(count for count, _ in met.values())
    whole = sum(most for _, most in met.values())
    stopped = sum(1 for count, most in met.values() if count < most)
    return ran, whole, stopped


def with_worlds(recorded, worlds):
    """Return recorded with a RacedAnswer for each candidate a race stopped early."""
    raced = dict(recorded)
    for candidate_id, (count, most) in worlds.items():
        if candidate_id in raced and count < most:
            raced[candidate_id] = RacedAnswer(objectives_of(raced[candidate_id]), count, False)
    return raced


def recorded_evaluations(record):
    """
    Return {candidate id: objectives} of every candidate the bag holds a result for.

    Objectives told to the optimizer (summaries) come first; then the first successful
    Evaluation of each candidate not told yet (the batch in flight when the run stopped).
    Where the answers carry outcome descriptors (a quality-diversity archive's,
    core.outcomes), the value is a core.outcomes.Answer with them (`told_outcomes`).
    """
    recorded = told_objectives(record)
    rows = evaluation_rows(record)
    for index in np.flatnonzero(rows.ok):
        candidate_id = int(rows.candidate_id[index])
        objectives = rows.objectives[index]
        if candidate_id not in recorded and np.all(np.isfinite(objectives)):
            recorded[candidate_id] = objectives.copy()
    return with_worlds(with_outcomes(recorded, told_outcomes(record, rows)),
                       told_worlds(record))


def told_answers(record):
    """Return {candidate id: objectives, Answer or RacedAnswer} as told to the optimizer."""
    return with_worlds(with_outcomes(told_objectives(record), told_outcomes(record)),
                       told_worlds(record))


def told_outcomes(record, rows=None):
    """
    Return {candidate id: (outcome names, values)} of the answers taken, where they have any.

    A candidate's answer taken is its 'ok' Evaluation (`evaluation_rows`); of the answers
    with the same objectives bit for bit, the outcomes most of them gave (the first on ties),
    as core.run.audits takes an answer that two evaluators agree on. Empty for a bag recorded
    before Evaluations had outcomes, or of a run without outcome descriptors.
    """
    evaluations = record.evaluations
    if not len(evaluations) or 'outcome_names' not in evaluations:
        return {}
    rows = evaluation_rows(record) if rows is None else rows
    answered = np.flatnonzero(np.isin(rows.status, ('ok', 'duplicate')))
    taken = {int(rows.candidate_id[index]): index for index in answered
             if rows.status[index] == 'ok'}
    votes = {}
    for index in answered:
        candidate_id = int(rows.candidate_id[index])
        names = tuple(evaluations['outcome_names'][index])
        first = taken.get(candidate_id)
        if not names or first is None or (rows.objectives[index].tobytes()
                                          != rows.objectives[first].tobytes()):
            continue
        values = np.asarray(evaluations['outcomes'][index], dtype=float).reshape(-1)
        votes.setdefault(candidate_id, collections.Counter())[
            (names, values[:len(names)].tobytes())] += 1
    return {candidate_id: (names, np.frombuffer(values, dtype=float).copy())
            for candidate_id, counter in votes.items()
            for (names, values), _ in counter.most_common(1)}


def with_outcomes(recorded, outcomes):
    """Return {id: objectives} with each id of `outcomes` an Answer holding them."""
    return {candidate_id: (Answer.of(values, *outcomes[candidate_id])
                           if candidate_id in outcomes else values)
            for candidate_id, values in recorded.items()}


def best_candidate_id(record):
    """
    Return the id of the run's best design.

    That is the optimizer's own choice in its last GenerationSummary (the lowest weighted sum
    for CMA-ES, the front's point closest to zero for MO-CMA-ES); for a hierarchy the best
    design of the structure the hierarchy chose, and for a run with resampled worlds the best
    of its final check on the fixed worlds (core.search.resampling; the search replayed from the
    bag, as the run's result, or its best so far when the run did not get there); without
    summaries (a bag cut early) the OK evaluation of lowest fitness.
    """
    if record.run_info is not None:
        best = _replayed_best(record)
        if best is not None:
            return best
    summary = last_summary(record)
    if summary is not None:
        return int(summary['best_candidate_id'])
    rows = evaluation_rows(record)
    ok = np.flatnonzero(rows.ok)
    if not len(ok):
        raise UserError(f'{record.path}: the bag holds no successful evaluation, so there is '
                        'no best design')
    return int(rows.candidate_id[ok[np.argmin(rows.fitness[ok])]])


def _replayed_best(record):
    """Return the best design's id of a hierarchical or resampled run (replayed), else None."""
    try:
        task = run_task_of(record)
    except UserError:
        return None
    if task.hierarchy is None and task.worlds.resample == 'none':
        return None
    search = Search(task)
    try:
        replay(search, recorded_evaluations(record))
    except OptimizerError:
        return None
    best = search.best
    return None if best is None else int(best[0].candidate_id)


def structure_bests(record):
    """
    Return [(structure, candidate id)] of every structure a hierarchical run checked, in order.

    Each is the structure's best design (the better of its optimizations), as the search
    replayed from the bag finds it; [] for a run without a hierarchy.
    """
    task = run_task_of(record)
    if task.hierarchy is None:
        return []
    search = Search(task)
    try:
        replay(search, recorded_evaluations(record))
    except OptimizerError as error:
        raise UserError(f'{record.path}: the recorded hierarchy run disagrees with a fresh '
                        f'search of its task and seed: {error}') from None
    return [(outcome.structure, int(outcome.result.candidate_id))
            for outcome in search.outcomes]


def replayed_optimizer(record, algorithms, single=False):
    """
    Return the optimizer of a run of one of `algorithms`, replayed from its bag, else None.

    The bag holds the evaluations, not the optimizer's state: the search is replayed from the
    told objectives (it is deterministic), and the outcome descriptors of the answers taken
    (`told_answers`), which rebuilds it exactly as the run had it. A hierarchy or two-stage
    run gives its last optimization's, or None if `single`.
    """
    try:
        task = run_task_of(record)
    except UserError:
        return None
    if task.algorithm not in algorithms or (
            single and (task.hierarchy is not None or task.two_stage)):
        return None
    search = Search(task)
    try:
        replay(search, told_answers(record))
    except OptimizerError:
        return None
    return search.optimizer


def restarts_of(record):
    """
    Return the core.search.restarts Restart records of a run of ipop-cma or bipop-cma, else [].

    Replayed (replayed_optimizer): every CMA-ES instance, the generation it started at, its
    population, step size, regime and why the one before it ended. Only for a run of one
    optimization: a hierarchy's or a two-stage task's optimizers count generations each from 0.
    """
    optimizer = replayed_optimizer(record, RESTART_ALGORITHMS, single=True)
    return [] if optimizer is None else list(optimizer.restarts)


def archive_of(record):
    """
    Return the core.search.quality_diversity optimizer of a cma-mae or cma-me run, else None.

    Replayed (replayed_optimizer): the descriptors are computed from the genomes (and the
    outcome descriptors read from the Evaluations), so the archive comes back exactly as the
    run had it, elites, candidate ids and all.
    """
    return replayed_optimizer(record, QD_ALGORITHMS)


def final_design(bag):
    """Return (task, normalized genome, structure) of a finished run's best design."""
    record = open_run(bag, warn=False)
    summary = last_summary(record)
    if summary is not None and summary['final'] and len(np.ravel(summary['best_genome'])):
        structure = tuple(int(joints) for joints in np.ravel(summary['structure']))
        x = np.asarray(summary['best_genome'], dtype=float).ravel()
    else:
        design = recorded_design(record, best_candidate_id(record))
        structure, x = design.structure, design.x
    return run_task_of(record, Variant(structure=tuple(structure or ()))), x, structure


def ranked_candidate_id(record, generation=None, rank=0):
    """Return the id of the rank-th best (lowest fitness) OK evaluation, of one generation."""
    rows = evaluation_rows(record)
    mask = rows.ok.copy()
    where = 'the run'
    if generation is not None:
        mask &= rows.generation == generation
        where = f'generation {generation}'
    chosen = np.flatnonzero(mask)
    if not len(chosen):
        generations = sorted(set(rows.generation[rows.ok].tolist()))
        span = f'{generations[0]}..{generations[-1]}' if generations else 'none'
        raise UserError(f'{record.path}: no successful evaluation in {where} (generations '
                        f'in the bag: {span})')
    order = chosen[np.lexsort((rows.candidate_id[chosen], rows.fitness[chosen]))]
    if not 0 <= rank < len(order):
        raise UserError(f'--rank {rank}: {where} has {len(order)} evaluated designs; expected '
                        f'a rank from 0 to {len(order) - 1}')
    return int(rows.candidate_id[order[rank]])


_UNITS = (('hand.base_position_', 'm'), ('hand.base_yaw', 'rad'), ('.length', 'm'),
          ('.position_x', 'm'), ('.position_z', 'm'),
          ('_angle', 'rad'), ('_limit', 'rad'), ('controller.target.', 'rad'),
          ('controller.torque.', 'N m'), ('controller.kp.', 'N m / rad'),
          ('controller.kd.', 'N m s / rad'), ('friction', ''))


def gene_unit(name):
    """Return the physical unit of a gene, from its name ('' for a coefficient)."""
    for marker, unit in _UNITS:
        if marker in name:
            return unit
    return ''
