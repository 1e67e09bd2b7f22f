"""
The run of a co-design as events and a clock: what the optimizer node decides, without ROS.

A RunController owns the run's Search, a Dispatcher, the results of the batch in flight and
the summaries. It is driven by what the optimizer hears (`heard_from` a heartbeat,
`evaluated`, `rejected`) and by `tick()`, and answers through an outbox with four methods:

    send_candidate(candidate, evaluator_id, attempt, genome_names, design)
                                   # design: its core.sim.physical.PhysicalDesign (SI units)
    send_summary(summary)          # a core.run.summary mapping; the last one has final=True;
                                   # its 'best_design' holds the best design so far as
                                   # core.sim.geometry Shapes, for a 3D viewer
    log(text, level='info')        # a line for whoever watches the run ('warning')
    finish(result)                 # the run ended; result is the record of `result.json`

The clock (a function returning seconds, `time.monotonic` by default) is the only source of
time, so a test drives a whole run, heartbeats, deadlines and silent evaluators included,
with a fake one. Rules the controller adds to the Dispatcher's:

- the run starts once `evaluators_expected` evaluators are alive and the node says that its
  subscribers (recorders) are there; until then nothing is sent;
- a batch is told to the search when every candidate of it has its first accepted answer;
- with `evaluation_timeout` 0 the deadline adapts: 20 times the slowest of the last 50
  evaluations, at least 60 s (3600 s until the first one comes back);
- a resumed run (core.search.resume.ResumePoint) starts from the rebuilt search and does not send
the
  candidates whose objectives its record already holds;
- an answer is taken only as core.run.audits decides: some go to a second evaluator first, a
  mismatch to a third, and a liar is quarantined (its untold answers are evaluated again).
  Audits are cost, not progress: neither the evaluations told nor the rate count them.
- the progress line's rate and time left count only the evaluations this process sent: a
  resumed run's replayed record took no time here;
- with racing (`worlds: {racing: ...}`) a generation goes out in rounds (core.run.rounds): each
  round waits for all its answers, then the race stops the candidates that can no longer be
  selected; the batch is told when the race is done. A hierarchy's or resampling's checks are
  not raced.
"""

import collections
import json
import os
import time

from hand_codesign.core.contract import EVALUATORS_READY
from hand_codesign.core.outcomes import Answer
from hand_codesign.core.outcomes import objectives_of
from hand_codesign.core.run.audits import Audits
from hand_codesign.core.run.audits import DEFAULT_FRACTION
from hand_codesign.core.run.dispatch import Dispatcher
from hand_codesign.core.run.rounds import RaceRounds
from hand_codesign.core.run.runs import engines_text, engines_version, library_versions
from hand_codesign.core.run.summary import generation_summary
from hand_codesign.core.run.summary import progress_line
from hand_codesign.core.search.search import Search
from hand_codesign.core.sim.geometry import design_shapes
from hand_codesign.core.sim.physical import candidate_design
from hand_codesign.core.task.genome import genome_spec
from hand_codesign.outputs import staged
import numpy as np

FIRST_EVALUATION_TIMEOUT = 3600.0
ADAPTIVE_FACTOR = 20.0
ADAPTIVE_MINIMUM = 60.0
ADAPTIVE_WINDOW = 50
# a candidate may go to its first evaluator, an auditor, a third, and again after a quarantine
MAX_ATTEMPTS = 8


def default_run_id(task):
    """Return a run id unique on this host: the task's name, the time and the process id."""
    return f'{task.name}-{time.strftime("%Y%m%d-%H%M%S")}-{os.getpid()}'


class RunController:
    """Drive a run's search over evaluators, one batch at a time (see the module doc)."""

    def __init__(self, task, run_id, outbox, resumed=None, heartbeat_timeout=5.0,
                 evaluation_timeout=0.0, evaluators_expected=1, clock=time.monotonic,
                 audit_fraction=DEFAULT_FRACTION, own_evaluators=()):
        self.task = task
        self.run_id = run_id
        self.outbox = outbox
        self.resumed = resumed
        self.search = resumed.search if resumed is not None else Search(task)
        self.told = resumed.evaluations_told if resumed is not None else 0
        # what a resumed run's record holds (its told batches and the pending batch's known
        # answers) is told here without being evaluated here
        self.replayed = self.told + (len(resumed.known) if resumed is not None else 0)
        self.evaluators_expected = evaluators_expected
        self.clock = clock
        self.dispatcher = Dispatcher(heartbeat_timeout,
                                     evaluation_timeout or FIRST_EVALUATION_TIMEOUT,
                                     MAX_ATTEMPTS)
        self.audits = Audits(task.seed, audit_fraction, own_evaluators)
        self.rejected_evaluations = 0  # Evaluations whose signature failed
        self.attempts = {}             # candidate id -> dispatches so far
        self.adaptive_timeout = evaluation_timeout <= 0
        self.wall_times = collections.deque(maxlen=ADAPTIVE_WINDOW)
        self.batch = None
        self.rounds = None  # RaceRounds of a raced batch in flight (core.run.rounds)
        self.genome_names = ()
        self.physical = {}  # candidate id -> PhysicalDesign of the batch in flight
        self.results = {}
        self.last_summary = None
        self.started = None
        self.finished = False

    def run_info(self):
        """Return the fields of the run's RunInfo announcement (all but its stamp)."""
        task = self.task
        return {
            'run_id': self.run_id, 'task_name': task.name, 'task_yaml': task.source_text,
            'seed': task.seed, 'algorithm': task.algorithm, 'iterations': task.iterations,
            'population': task.population, 'world_states': task.num_world_states,
            'objective_names': list(task.objective_names), 'versions': library_versions(),
            'resumed_from': self.resumed.run_id if self.resumed is not None else '',
            'engine': engines_text(task), 'engine_version': engines_version(engines_text(task))}

    def describe(self):
        """Return the line announcing the run."""
        task = self.task
        return (f'run {self.run_id}: task {task.name}, {task.algorithm}, '
                f'{task.iterations} generations x {task.population}, '
                f'{task.num_world_states} world states, seed {task.seed}; '
                f'waiting for {self.evaluators_expected} evaluator(s)')

    def ours(self, run_id):
        return run_id == self.run_id

    def heard_from(self, evaluator_id, capacity, run_id=''):
        """Take a heartbeat of an evaluator serving this run ('' serves every run)."""
        if run_id in ('', self.run_id):
            self.dispatcher.heard_from(evaluator_id, capacity, self.clock())
            self.advance()

    def evaluated(self, run_id, candidate_id, evaluator_id, objectives, wall_time,
                  outcome_names=(), outcomes=(), evaluation=None):
        """
        Take an evaluation: the first answer, or an audit's, per core.run.audits' rules.

        With outcome descriptors (core.outcomes, a quality-diversity archive's) the answer
        told is a core.outcomes.Answer, else the objectives alone. `evaluation`: the whole
        Evaluation (any object with its fields), which a raced batch's round reads (its
        attempt, world_objectives and collision; core.run.rounds).
        """
        raced = self.rounds is not None
        if (not self.ours(run_id) or evaluator_id in self.audits.quarantined
                or (raced and self.rounds.stale(candidate_id, evaluation.attempt))
                or self.audits.answered(candidate_id, evaluator_id)
                or not self.dispatcher.complete(candidate_id)):
            return
        self.wall_times.append(wall_time)
        others = set(self.dispatcher.live_evaluators(self.clock())) - {evaluator_id}
        answer = (RaceRounds.answer(objectives, evaluation) if raced
                  else Answer.of(objectives, outcome_names, outcomes) if len(outcome_names)
                  else objectives)
        verdict = self.audits.take(candidate_id, evaluator_id, answer, bool(others))
        if verdict.value is not None:
            self.results[candidate_id] = verdict.value
        elif verdict.exclude:
            self._send_again(candidate_id, verdict.exclude)
            if len(verdict.exclude) > 1:
                self.outbox.log(f'candidate {candidate_id}: {", ".join(sorted(verdict.exclude))}'
                                ' disagree; asking another evaluator', 'warning')
        for liar in verdict.liars:
            self.dispatcher.quarantine(liar)
            self.outbox.log(f'evaluator {liar} returned objectives that others contradict: '
                            'quarantined, its answers are evaluated again', 'warning')
        self.results.update(verdict.released)
        for redone in verdict.redo:
            self.results.pop(redone, None)
            self._send_again(redone, ())
        self.advance()

    def _take_unauditable(self):
        """Take the audits whose auditors are all gone with their one answer (core.run.audits)."""
        for candidate_id in self.dispatcher.stranded(self.clock()):
            released = self.audits.take_unaudited(candidate_id)
            if released:
                self.dispatcher.withdraw(candidate_id)
                self.results.update(released)
                self.outbox.log(f'candidate {candidate_id}: no other evaluator alive to audit '
                                'it; its answer is taken unaudited', 'warning')

    def _send_again(self, candidate_id, exclude):
        candidate = (self.rounds.unit(candidate_id) if self.rounds is not None
                     else next(c for c in self.batch if c.candidate_id == candidate_id))
        self.dispatcher.add_again(candidate, self.attempts.get(candidate_id, 0), exclude)

    def forged(self, run_id, evaluator_id):
        """Count an Evaluation of this run whose signature failed; it is otherwise ignored."""
        if not self.ours(run_id):
            return
        self.rejected_evaluations += 1
        if self.rejected_evaluations in (1, 10, 100, 1000):
            self.outbox.log(f'{self.rejected_evaluations} evaluation(s) with a missing or '
                            f'wrong signature ignored (latest claims to be {evaluator_id!r})',
                            'warning')

    def rejected(self, run_id, candidate_id, evaluator_id, reason):
        """Take a rejection: the candidate goes to an evaluator that has not refused it."""
        if self.ours(run_id) and self.dispatcher.reject(candidate_id, evaluator_id, reason):
            self.outbox.log(f'candidate {candidate_id} rejected by {evaluator_id}: {reason}',
                            'warning')

    def tick(self, subscribers_ready=True):
        """Start the run when ready, then catch silent evaluators and overdue candidates."""
        if self.started is None and subscribers_ready and self._enough_evaluators():
            self.started = self.clock()
            self.outbox.log(EVALUATORS_READY)
        self.advance()

    def _enough_evaluators(self):
        return len(self.dispatcher.live_evaluators(self.clock())) >= self.evaluators_expected

    def advance(self):
        """Send what can be sent; tell the batch when complete and start the next one."""
        while self.started is not None and not self.finished:
            if self.batch is None:
                if self.search.stop():
                    self._finish()
                    return
                self._start_batch()
            if self.adaptive_timeout and self.wall_times:
                self.dispatcher.evaluation_timeout = max(
                    ADAPTIVE_MINIMUM, ADAPTIVE_FACTOR * max(self.wall_times))
            for candidate, evaluator_id, attempt in self.dispatcher.assignments(self.clock()):
                self.attempts[candidate.candidate_id] = attempt + 1
                self.outbox.send_candidate(candidate, evaluator_id, attempt, self.genome_names,
                                           self._physical(candidate))
            self._take_unauditable()
            if self.dispatcher.unfinished or self.audits.holding:
                return
            if self.rounds is not None and not self._race_done():
                continue  # the next round was queued: send it
            self._tell_batch()

    def _start_batch(self):
        self.batch = self.search.ask()
        self.audits.start_batch()
        self.genome_names = genome_spec(self.search.batch_task).names
        self.physical = {}
        # a resumed run's first batch may be partly evaluated already (in its record)
        known = self.resumed.known if self.resumed is not None else {}
        self.results = {candidate.candidate_id: known[candidate.candidate_id]
                        for candidate in self.batch if candidate.candidate_id in known}
        racing = self.task.worlds.racing
        if racing is not None and not self.search.checking:
            self.rounds = RaceRounds(self.batch, self.search.batch_task,
                                     self.search.optimizer.selected, racing)
            self._start_round()
            return
        self.dispatcher.add([candidate for candidate in self.batch
                             if candidate.candidate_id not in self.results])

    def _start_round(self):
        """Queue the race's current round (core.run.rounds), its attempts continuing."""
        units = self.rounds.units(self.attempts)
        self.results = {}
        self.audits.start_batch()
        self.dispatcher.add(units, self.rounds.first_attempts)

    def _race_done(self):
        """Give the race the round's answers; queue the next round, or return True when done."""
        if not self.rounds.finish_round(self.results, self.audits.audited):
            self._start_round()
            return False
        self.results = self.rounds.answers()
        return True

    def _physical(self, candidate):
        """Return a candidate's design in SI units, made once per batch (re-sends reuse it)."""
        design = self.physical.get(candidate.candidate_id)
        if design is None:
            design = self.physical[candidate.candidate_id] = candidate_design(
                self.search.batch_task, candidate.x)
        return design

    def _tell_batch(self):
        checking = self.search.checking
        structure = self.search.batch_task.structure
        optimizer = self.search.optimizer
        self.search.tell(self.results)
        self.told += len(self.batch)
        told_ids = [candidate.candidate_id for candidate in self.batch]
        objectives = np.array([objectives_of(self.results[candidate_id])
                               for candidate_id in told_ids])
        generation, variant = self.batch[0].generation, self.batch[0].variant
        horizon, stage = variant.horizon, variant.stage
        rounds, self.rounds = self.rounds, None
        self.batch = None
        elapsed = self.clock() - self.started
        result = self.search.summary_result(optimizer)
        summary = generation_summary(
            generation, structure, self.task.objective_names, told_ids, objectives,
            result, self.told, elapsed, checking, horizon)
        summary['best_design'] = self.best_design(structure, result.x)
        audited = self.audits.audited if rounds is None else rounds.audited
        summary.update(self.trust_counts(), audited_ids=sorted(audited))
        summary['told_worlds'] = ([] if rounds is None else
                                  [self.results[candidate_id].worlds for candidate_id in told_ids])
        summary['stage'] = stage  # for the progress line; the candidates carry it
        summary.update(restart_facts(optimizer, generation))
        self.outbox.send_summary(summary)
        if checking and self.search.resampled:
            self.outbox.log(
                f'final check on the fixed worlds of the best designs of the last '
                f'{len(told_ids)} generations: candidate {result.candidate_id} is the result, '
                + ', '.join(f'{name} {value:.4g}'
                            for name, value in zip(self.task.objective_names, result.objectives)))
            return
        if checking:
            seeds = ', '.join(str(seed) for seed in self.search.outcomes[-1].seeds)
            self.outbox.log(
                f'structure {list(structure)} (optimized with seeds {seeds}): best design on '
                'the held-out worlds: '
                + ', '.join(f'{name} {value:.4g}'
                            for name, value in zip(self.task.objective_names, objectives[0])))
            return
        self.last_summary = summary
        # a budget of evaluations: with restarts (core.search.restarts) generations grow
        rate = (self.told - self.replayed) / max(elapsed, 1e-9)  # a fake clock may not move
        to_go = self.task.iterations * self.task.population - optimizer.evaluations
        left = to_go / rate if rate > 0 else None
        line = progress_line(summary, self.task.iterations, rate, left)
        if self.audits.audit_evaluations:
            line += f' | {self.audits.audit_evaluations} audit evaluations'
        self.outbox.log(line)

    def trust_counts(self):
        """Return the run's counts of forged answers, audits and quarantines so far."""
        return {'rejected_evaluations': self.rejected_evaluations,
                'audit_evaluations': self.audits.audit_evaluations,
                'reevaluations': self.audits.reevaluations,
                'quarantined': list(self.audits.quarantined)}

    def _finish(self):
        self.finished = True
        stop_reason = ', '.join(f'{key}={value}' for key, value in self.search.stop().items())
        result, structure = self.search.best
        names = self.task.objective_names
        # after a resume, the last batch may have been a hierarchy check: no generation yet
        last = self.last_summary or generation_summary(
            self.search.optimizer.generation, structure, names, [result.candidate_id],
            result.objectives.reshape(1, -1), result, self.told, 0.0)
        self.outbox.send_summary(dict(
            last, final=True, stop_reason=stop_reason, told_ids=[],
            told_objectives=np.zeros((0, len(names))), wall_time=self.clock() - self.started,
            structure=structure, best_id=result.candidate_id,
            best_objectives=result.objectives, best_fitness=result.fitness,
            best_x=result.x, best_design=self.best_design(structure, result.x),
            audited_ids=[], told_worlds=[], **self.trust_counts()))
        self.outbox.log(f'run {self.run_id} finished ({stop_reason})')
        self.outbox.finish(self._result(result, structure, stop_reason))

    def best_design(self, structure, x):
        """Return the core.sim.geometry Shapes of the design of genome x of a hand structure."""
        task = self.task.replace(structure=structure)
        return design_shapes(task, genome_spec(task).decode(x))

    def _result(self, result, structure, stop_reason):
        checked = [{'candidate_id': design.check_id, 'repeats': design.candidate_id,
                    'generation': design.generation, 'draw_fitness': design.draw_fitness,
                    'fitness': design.fitness} for design in self.search.final_check]
        return {
            'run_id': self.run_id, 'task': self.task.name, 'seed': self.task.seed,
            'stop_reason': stop_reason, 'evaluations': self.told,
            'structure': list(structure), 'trust': self.trust_counts(),
            'best_candidate_id': result.candidate_id, 'generation': result.generation,
            'horizon': self.search.horizon_of(result.generation),
            'fitness': result.fitness,
            'objectives': dict(zip(self.task.objective_names, result.objectives.tolist())),
            'design': genome_spec(self.task.replace(structure=structure)).design_values(
                result.x),
            **({'final_check': checked} if checked else {}),
        }


def restart_facts(optimizer, generation):
    """
    Return the summary entries of a restart run's generation (core.search.restarts), else {}.

    restart: the index of the CMA-ES instance that asked the generation; population: that
    instance's population; spent and budget: the optimizer's evaluations told and budget. The
    GenerationSummary message has no field for them (its told_ids show each generation's size,
    and a replay of the told objectives gives every restart); the progress line shows them.
    """
    restart_of = getattr(optimizer, 'restart_of', None)
    if restart_of is None:
        return {}
    instance = restart_of(generation)
    return {'restart': instance.index, 'population': instance.population,
            'spent': optimizer.evaluations, 'budget': optimizer.budget}


def write_result(path, result, published):
    """Write a run's result (RunController's finish) and the messages it published as JSON."""
    with staged(path) as temporary:   # whole or not at all: readers take it as the result
        with open(temporary, 'w', encoding='utf-8') as stream:
            json.dump(dict(result, published=published), stream, indent=2)
