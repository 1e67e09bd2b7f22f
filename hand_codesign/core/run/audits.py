"""
Audits: which answers a second evaluator checks before a generation is told, and who lied.

An evaluation is a deterministic function of its Candidate and RunInfo, so two honest
evaluators return the same objectives bit for bit; a signature proves who answered, an audit
whether the answer is right. Rules (the RunController applies them to each answer):

- an answer is audited when its candidate is drawn (probability `fraction`, a draw of the
  run's seed and the candidate id, so the same candidates are drawn in every run of a seed)
  and its evaluator is not one of the run's own, or when it is the first answer of an
  evaluator that has not yet passed an audit in this run (probation). Its further answers are
  held, untold, until that audit is settled: taken if it passed, evaluated again by others if
  it failed. So an evaluator that lies on every evaluation is caught on its first answer,
  before any of its answers is told, and the result equals that of a run without it, for one
  extra evaluation per honest evaluator;
- the run's own evaluators (`own`: the roles `hand-codesign run` started on the optimizer's
  host, with keys it never wrote to a file) are the same code on the same machine as the
  optimizer: a drawn audit of theirs would cost a tenth of the run and catch nothing their
  probation does not (a different build, a non-deterministic set-up), so only their
  probation is audited;
- the audit goes to another evaluator; when both agree bit for bit, the value stands and both
  evaluators have passed. When they differ, a third evaluator (and so on) is asked until two
  answers agree; every evaluator that answered otherwise is quarantined;
- everything a quarantined evaluator returned that is not yet told is evaluated again, by
  others, and nothing it answers later is taken;
- answers are audited only while another evaluator is alive to do it (a run with a single
  evaluator has no one to compare with); an audit that no live evaluator may do any more (its
  auditor died and only the first evaluator is left) is taken with its one answer
  (`take_unaudited`), with the answers held for that evaluator's probation, so that a run
  never waits without end for an auditor.

An answer is an objective vector, or a core.outcomes.Answer when the run's archive spans
outcome descriptors: two answers agree when objectives and outcomes agree bit for bit, and the
value taken is the first agreeing evaluator's whole answer. A racing round's answer
(core.search.racing.RoundAnswer) agrees when its objectives, its worlds' objectives and its
start check agree; a batch's rounds are audited each as a batch of its own.

What this buys against an evaluator that lies rarely, after its probation: each lie is
caught with probability `fraction`, so one that lies k times goes unnoticed with probability
(1 - fraction)^k, and the lies told before it is caught stay in the search's history.
"""

import collections

from hand_codesign.core.run.supervision import serves_role
import numpy as np

DEFAULT_FRACTION = 0.1
AUDIT_STREAM = 0x61756469  # "audi": keeps these draws apart from the run's other streams


def drawn(seed, candidate_id, fraction):
    """Return whether the run's seed draws this candidate for an audit."""
    if fraction <= 0:
        return False
    return np.random.default_rng([AUDIT_STREAM, seed, candidate_id]).random() < fraction


class Verdict:
    """What became of an answer: its settled value, or who else must be asked."""

    def __init__(self, value=None, exclude=(), liars=(), redo=(), released=None):
        self.value = value            # the settled objectives, or None
        self.exclude = set(exclude)   # ask another evaluator than these (empty: nobody)
        self.liars = list(liars)      # evaluators quarantined by this answer
        self.redo = list(redo)        # candidates whose told-to-be values came from liars
        self.released = released or {}  # held answers now settled: candidate id -> value


class Audits:
    """The audit state of a run (see the module doc)."""

    def __init__(self, seed, fraction=DEFAULT_FRACTION, own=()):
        self.seed = seed
        self.fraction = fraction
        self.own = frozenset(own)  # roles of the run's own evaluators (core.run.supervision)
        self.passed = set()        # evaluators that agreed with another in an audit
        self.quarantined = []      # in the order they were caught
        self.audit_evaluations = 0
        self.reevaluations = 0
        self.audited = set()       # candidates of the batch in flight that were audited
        self._answers = {}         # candidate id -> [(evaluator, objectives)], unsettled
        self._source = {}          # settled by one answer: candidate id -> its evaluator
        self._probation = {}       # evaluator -> the candidate of its first audit, pending
        self._held = {}            # evaluator on probation -> its other answers' candidates

    def start_batch(self):
        self.audited = set()
        self._answers = {}
        self._source = {}
        self._probation = {}
        self._held = {}

    @property
    def holding(self):
        """Return whether answers wait for their evaluator's probation audit."""
        return any(self._held.values())

    def answered(self, candidate_id, evaluator_id):
        """Return whether this evaluator's answer to the candidate is already counted."""
        return any(evaluator == evaluator_id for evaluator, _ in
                   self._answers.get(candidate_id, ()))

    def take(self, candidate_id, evaluator_id, answer, others_alive):
        """
        Record an accepted answer; return its Verdict. others_alive: could anyone audit.

        `answer`: the objectives, or a core.outcomes.Answer (objectives and outcomes).
        """
        if not hasattr(answer, 'fingerprint'):  # an Answer or a racing round's keeps its kind
            answer = np.asarray(answer, dtype=float)
        answers = self._answers.setdefault(candidate_id, [])
        answers.append((evaluator_id, answer))
        if len(answers) > 1:
            self.audit_evaluations += 1
            return self._compare(candidate_id, answers)
        on_probation = self.fraction > 0 and evaluator_id not in self.passed and others_alive
        first_on_probation = on_probation and evaluator_id not in self._probation
        if first_on_probation or (others_alive and not serves_role(evaluator_id, self.own)
                                  and drawn(self.seed, candidate_id, self.fraction)):
            if first_on_probation:
                self._probation[evaluator_id] = candidate_id
            self.audited.add(candidate_id)
            return Verdict(exclude={evaluator_id})
        if on_probation:
            self._held.setdefault(evaluator_id, []).append(candidate_id)
            return Verdict()
        return Verdict(value=self._settle_alone(candidate_id))

    def take_unaudited(self, candidate_id):
        """
        Settle an audit no live evaluator can do with its one answer; return {id: value}.

        Returns {} when the candidate is not an audit waiting on one answer. The evaluator
        stays unproven (a later audit may still catch it), but its held answers are released.
        """
        answers = self._answers.get(candidate_id, ())
        if len(answers) != 1:
            return {}
        evaluator_id = answers[0][0]
        released = {candidate_id: self._settle_alone(candidate_id)}
        self.audited.discard(candidate_id)
        if self._probation.get(evaluator_id) == candidate_id:
            del self._probation[evaluator_id]
            for held in self._held.pop(evaluator_id, []):
                released[held] = self._settle_alone(held)
        return released

    def _settle_alone(self, candidate_id):
        evaluator_id, objectives = self._answers.pop(candidate_id)[0]
        self._source[candidate_id] = evaluator_id
        return objectives

    def _compare(self, candidate_id, answers):
        votes = collections.Counter(_fingerprint(value) for _, value in answers)
        value, count = votes.most_common(1)[0]
        if count < 2:
            return Verdict(exclude={evaluator for evaluator, _ in answers})
        del self._answers[candidate_id]
        agreed = next(answer for _, answer in answers if _fingerprint(answer) == value)
        liars, released = [], {}
        for evaluator, objectives in answers:
            if _fingerprint(objectives) == value:
                self.passed.add(evaluator)
                self._probation.pop(evaluator, None)
                for held in self._held.pop(evaluator, []):
                    released[held] = self._settle_alone(held)
            elif evaluator not in self.quarantined:
                liars.append(evaluator)
        redo = []
        for liar in liars:
            redo += self.quarantine(liar)
        return Verdict(value=agreed, liars=liars, redo=redo, released=released)

    def quarantine(self, evaluator_id):
        """Quarantine an evaluator; return the candidates whose value only it gave (redo)."""
        self.quarantined.append(evaluator_id)
        self.passed.discard(evaluator_id)
        redo = sorted(candidate_id for candidate_id, source in self._source.items()
                      if source == evaluator_id)
        for candidate_id in redo:
            del self._source[candidate_id]
        self._probation.pop(evaluator_id, None)
        held = self._held.pop(evaluator_id, [])
        for candidate_id in held:
            del self._answers[candidate_id]
        redo += held
        for answers in self._answers.values():
            answers[:] = [(evaluator, value) for evaluator, value in answers
                          if evaluator != evaluator_id]
        self.reevaluations += len(redo)
        return redo


def _fingerprint(answer):
    """Return the bytes two agreeing answers share (objectives, and outcomes if any)."""
    return answer.fingerprint() if hasattr(answer, 'fingerprint') else answer.tobytes()
