"""
What an evaluator does with the messages it hears, without ROS.

Which candidates it takes, and what exactly it evaluates for each.

An evaluation is a pure function of its Candidate and the run's RunInfo (DESIGN.md):
`evaluation_job(run, candidate)` is that function's one home, turning the two messages (any
objects with their fields) into the task, genome and worlds that `core.evaluate` takes.
Whatever a Candidate carries that changes an evaluation is read there and nowhere else.

`EvaluatorInbox` holds the rules of taking candidates: only those addressed to this evaluator
(or to any), of the run it serves (or of any run), each (run, candidate, attempt) once; a
candidate that overtook its run's RunInfo (another topic) waits for it, at most
`run_info_wait` seconds, after which it is taken to be rejected for the missing RunInfo.
An inbox given a core.run.signing.Credential takes only RunInfos and Candidates whose signatures
hold (a candidate's covers its run's RunInfo, so it waits for that) and counts the others in
`rejected`; without one (an unsigned run) it takes every message.
"""

import dataclasses
import importlib.util
import time
from typing import Optional, Sequence, Tuple

from hand_codesign.core.run.runs import engine_names, engines_version, run_task
from hand_codesign.core.run.signing import run_digest
from hand_codesign.core.sim.worlds import world_states
from hand_codesign.core.task.genome import genome_spec
from hand_codesign.core.task.variant import Variant
import numpy as np

RUN_INFO_WAIT = 10.0


class CandidateRejected(Exception):
    """A candidate that cannot be evaluated; the message says why."""


@dataclasses.dataclass(frozen=True)
class EvaluationJob:
    """What to evaluate for a candidate: `core.evaluate(genome, task, worlds)`."""

    task: object
    genome: np.ndarray
    worlds: Optional[Sequence] = None  # None: every world state of the task
    share: Optional[Tuple[int, int]] = None  # a racing round's (first, end) of them; None: all


def job_key(candidate):
    """Return (run id, Variant): what decides a Candidate message's task, with its RunInfo."""
    return candidate.run_id, candidate_variant(candidate)


def candidate_variant(candidate):
    """
    Return the Variant a Candidate message (or anything with its fields) is evaluated on.

    The message carries the Variant's fields flat (msg_defs/Candidate.msg); a sender older
    than a field leaves it out, which means the field's default: a single-stage task (stage),
    the run's worlds (held_out_worlds), the run's fixed worlds (world_draw).
    """
    return Variant(structure=tuple(int(joints) for joints in candidate.structure),
                   world_states=int(candidate.world_states),
                   horizon=float(candidate.horizon),
                   stage=int(getattr(candidate, 'stage', 0)),
                   held_out=bool(getattr(candidate, 'held_out_worlds',
                                         getattr(candidate, 'held_out', False))),
                   world_draw=int(getattr(candidate, 'world_draw', 0)))


def check_engine(run):
    """
    Raise CandidateRejected if run's physics engines (RunInfo) are not this process's.

    RunInfo.engine names them comma-separated and engine_version their versions in the same
    order (core.run.runs); an evaluator that cannot import one of them, or has another version
    of one, refuses the run in one line.
    """
    engine = getattr(run, 'engine', '')  # '' from a sender older than the field
    wanted = getattr(run, 'engine_version', '')
    if not engine:
        return
    try:
        names = engine_names(engine)
    except ValueError:
        return  # candidate_task names the unknown engine
    for name in names:
        if importlib.util.find_spec(name) is None:
            raise CandidateRejected(f'run {run.run_id} simulates with {engine}; this evaluator '
                                    f'cannot import {name}: install it or start the evaluator '
                                    'where it is')
    if wanted and engines_version(engine) != wanted:
        raise CandidateRejected(f'run {run.run_id} simulates with {wanted}; this evaluator has '
                                f'{engines_version(engine)}: results would differ')


def candidate_task(run, candidate):
    """Return (Task, GenomeSpec) a candidate of run is evaluated with; CandidateRejected."""
    check_engine(run)
    try:
        task = run_task(run.task_yaml, f'run {run.run_id} task', run.seed, run.iterations,
                        run.population, run.world_states, candidate_variant(candidate),
                        getattr(run, 'engine', ''))
        return task, genome_spec(task)
    except ValueError as error:
        raise CandidateRejected(f'unusable structure or task: {error}')


def evaluation_job(run, candidate, built=None):
    """
    Return the EvaluationJob of a Candidate of run (a RunInfo); raise CandidateRejected.

    built: (task, genome spec) of the candidate when already built for its `job_key`.
    """
    task, spec = candidate_task(run, candidate) if built is None else built
    genome = np.asarray(candidate.genome, dtype=float)
    expected = spec.size
    if genome.shape != (expected,):
        raise CandidateRejected(
            f'genome has {genome.size} values, structure {tuple(candidate.structure)} of task '
            f'{task.name} needs {expected}')
    if not np.all(np.isfinite(genome)):
        raise CandidateRejected('genome contains NaN or infinite values')
    return EvaluationJob(task, genome, share=candidate_share(candidate, task))


def candidate_share(candidate, task):
    """
    Return a Candidate's racing share (first, end) of its task's worlds, or None for all.

    Candidate.worlds_from / worlds_to (0, 0 from a sender older than the fields, or without
    racing: every world); raise CandidateRejected for a share outside the task's worlds.
    """
    first = int(getattr(candidate, 'worlds_from', 0))
    end = int(getattr(candidate, 'worlds_to', 0))
    if not first and not end:
        return None
    worlds = len(world_states(task))
    if not 0 <= first < end <= worlds:
        raise CandidateRejected(f'worlds {first} to {end}: expected a share within the '
                                f'{worlds} worlds of task {task.name}')
    return first, end


class EvaluatorInbox:
    """The runs an evaluator knows and the candidates it takes (see the module doc)."""

    def __init__(self, evaluator_id, wanted_run='', run_info_wait=RUN_INFO_WAIT,
                 clock=time.monotonic, credential=None):
        self.evaluator_id = evaluator_id
        self.credential = credential
        self.rejected = 0   # RunInfos and Candidates ignored: signature missing or wrong
        self.heard = 0      # RunInfos and Candidates given to it, its own or not
        self._digests = {}  # run id -> SHA-256 of its RunInfo, which candidates' signatures cover
        self.wanted_run = wanted_run
        self.run_info_wait = run_info_wait
        self.clock = clock
        self.runs = {}      # run id -> RunInfo
        self._tasks = {}    # job_key -> (Task, GenomeSpec), built once
        self._seen = set()  # (run id, candidate id, attempt) already taken
        self._waiting = {}  # run id -> [(candidate, arrival time)] that overtook their RunInfo

    def _serves(self, run_id):
        return not self.wanted_run or run_id == self.wanted_run

    def run_announced(self, run):
        """Take a RunInfo; return the candidates that were waiting for it."""
        self.heard += 1
        if not self._serves(run.run_id):
            return []
        if self.credential is not None:
            if not self.credential.run_info_valid(run):
                self.rejected += 1
                return []
            if run.run_id in self.runs:  # the first signed RunInfo of a run stays
                self.rejected += run_digest(run) != self._digests[run.run_id]
                return []
            self._digests[run.run_id] = run_digest(run)
        self.runs[run.run_id] = run
        return [candidate for candidate, _ in self._waiting.pop(run.run_id, [])
                if self._take(candidate)]

    def _take(self, candidate):
        """Return whether a candidate of a known run is signed (if need be) and new."""
        if self.credential is not None and not self.credential.candidate_valid(
                candidate, self._digests[candidate.run_id]):
            self.rejected += 1
            return False
        key = (candidate.run_id, candidate.candidate_id, candidate.attempt)
        if key in self._seen:
            return False
        self._seen.add(key)
        return True

    def candidate_arrived(self, candidate):
        """Return [candidate] if it is to be evaluated now, [] if not ours, seen or waiting."""
        self.heard += 1
        if candidate.evaluator_id not in ('', self.evaluator_id):
            return []
        if not self._serves(candidate.run_id):
            return []
        if candidate.run_id in self.runs:
            return [candidate] if self._take(candidate) else []
        # a candidate can overtake its run's RunInfo, which travels on another topic
        self._waiting.setdefault(candidate.run_id, []).append((candidate, self.clock()))
        return []

    def orphans(self):
        """Return the waiting candidates whose RunInfo did not come in time (to reject)."""
        now = self.clock()
        late = []
        for run_id, waiting in list(self._waiting.items()):
            if now - waiting[0][1] > self.run_info_wait:
                late += [candidate for candidate, _ in self._waiting.pop(run_id)]
        if self.credential is not None:  # without their RunInfo, no signature can hold
            self.rejected += len(late)
            return []
        return late

    def job(self, candidate):
        """Return the EvaluationJob of a taken candidate; raise CandidateRejected."""
        run = self.runs.get(candidate.run_id)
        if run is None:
            raise CandidateRejected(f'no RunInfo received for run "{candidate.run_id}"')
        key = job_key(candidate)
        if key not in self._tasks:
            self._tasks[key] = candidate_task(run, candidate)
        return evaluation_job(run, candidate, self._tasks[key])
