"""
Which evaluator evaluates which candidate: queueing, heartbeats, deadlines, re-dispatch.

The optimizer node drives a Dispatcher with what it hears (heartbeats, evaluations,
rejections) and the clock, and publishes what `assignments()` returns. Keeping this apart from
ROS makes the rules testable on their own and usable by any transport.

Rules:
- an evaluator is alive while its last heartbeat is younger than `heartbeat_timeout`;
- a live evaluator gets at most `capacity` candidates at once (what it announces), so it
  always has the next candidate queued while it evaluates one; but once no more candidates
  wait than there are live evaluators (two or more), none is sent for the first time to an
  evaluator that has one already: at the end of a generation the evaluator that is done first
  takes the next, instead of idling while another works off its queue;
- candidates of an evaluator that died go back to the front of the queue;
- a candidate unanswered after `evaluation_timeout` is sent again to another evaluator; the
  first answer wins, later ones are ignored as duplicates;
- a rejected candidate is sent to an evaluator that has not rejected it, and after
  `max_attempts` dispatches the dispatcher gives up with DispatchError;
- a candidate added again (`add_again`, an audit) goes to an evaluator other than those
  named, with the next attempt number;
- a quarantined evaluator gets nothing more, and its heartbeats are ignored.
"""

from collections import deque
from dataclasses import dataclass, field


class DispatchError(RuntimeError):
    """A candidate could not be evaluated by any evaluator."""


@dataclass
class EvaluatorState:
    capacity: int
    last_heard: float
    assigned: dict = field(default_factory=dict)  # candidate id -> time it was sent


@dataclass
class PendingCandidate:
    candidate: object
    attempts: int = 0
    rejected_by: set = field(default_factory=set)
    reasons: list = field(default_factory=list)


class Dispatcher:
    """Hand candidates to evaluators and take them back when evaluators fail."""

    def __init__(self, heartbeat_timeout=5.0, evaluation_timeout=120.0, max_attempts=5):
        self.heartbeat_timeout = heartbeat_timeout
        self.evaluation_timeout = evaluation_timeout
        self.max_attempts = max_attempts
        self.evaluators = {}
        self._pending = {}
        self._first_attempts = {}  # candidate id -> the attempt its dispatch budget counts from
        self._queue = deque()
        self.quarantined = set()

    def heard_from(self, evaluator_id, capacity, now):
        """Record a heartbeat of an evaluator announcing how many candidates it takes."""
        if evaluator_id in self.quarantined:
            return
        state = self.evaluators.get(evaluator_id)
        if state is None:
            self.evaluators[evaluator_id] = EvaluatorState(max(1, capacity), now)
        else:
            state.capacity = max(1, capacity)
            state.last_heard = now

    def add(self, candidates, first_attempts=None):
        """
        Queue candidates (objects with a `candidate_id`) for evaluation.

        first_attempts: candidate id -> the attempt number its dispatches start from (a
        racing round's further attempts, core.run.rounds); `max_attempts` counts from there.
        """
        first_attempts = first_attempts or {}
        for candidate in candidates:
            first = first_attempts.get(candidate.candidate_id, 0)
            if first:
                self._first_attempts[candidate.candidate_id] = first
            else:
                self._first_attempts.pop(candidate.candidate_id, None)
            self._pending[candidate.candidate_id] = PendingCandidate(candidate, first)
            self._queue.append(candidate.candidate_id)

    def add_again(self, candidate, attempts, exclude=()):
        """Queue a candidate once more, for an evaluator not in exclude, as attempt `attempts`."""
        self._pending[candidate.candidate_id] = PendingCandidate(
            candidate, attempts, set(exclude))
        self._queue.append(candidate.candidate_id)

    def quarantine(self, evaluator_id):
        """Send nothing more to an evaluator; what it holds goes back to the queue."""
        self.quarantined.add(evaluator_id)
        state = self.evaluators.pop(evaluator_id, None)
        if state is not None:
            for candidate_id in sorted(state.assigned, reverse=True):
                elsewhere = any(candidate_id in other.assigned
                                for other in self.evaluators.values())
                if candidate_id in self._pending and not elsewhere:
                    self._queue.appendleft(candidate_id)

    @property
    def unfinished(self):
        """Return how many added candidates have no accepted evaluation yet."""
        return len(self._pending)

    def stranded(self, now):
        """Return the queued candidates that every live evaluator is excluded from."""
        live = set(self.live_evaluators(now))
        return [candidate_id for candidate_id in self._queue
                if candidate_id in self._pending and live
                and live <= self._pending[candidate_id].rejected_by]

    def withdraw(self, candidate_id):
        """Stop dispatching a queued candidate (settled otherwise)."""
        self._pending.pop(candidate_id, None)

    def live_evaluators(self, now):
        return [evaluator_id for evaluator_id, state in self.evaluators.items()
                if now - state.last_heard <= self.heartbeat_timeout]

    def assignments(self, now):
        """Return the (candidate, evaluator_id, attempt) to send now."""
        self._reclaim_from_silent(now)
        self._requeue_overdue(now)
        live = set(self.live_evaluators(now))
        sent = []
        while self._queue:
            candidate_id = self._queue[0]
            pending = self._pending.get(candidate_id)
            if pending is None:
                self._queue.popleft()
                continue
            evaluator_id = self._least_loaded(pending, live)
            if evaluator_id is None:
                break
            self._queue.popleft()
            first = self._first_attempts.get(candidate_id, 0)
            if pending.attempts - first >= self.max_attempts:
                raise DispatchError(
                    f'candidate {candidate_id} was dispatched {pending.attempts} times without '
                    f'an evaluation; rejections: {"; ".join(pending.reasons) or "none"}')
            self.evaluators[evaluator_id].assigned[candidate_id] = now
            sent.append((pending.candidate, evaluator_id, pending.attempts))
            pending.attempts += 1
        return sent

    def complete(self, candidate_id):
        """Accept the first answer to a candidate, from any evaluator; False if unknown or done."""
        for state in self.evaluators.values():
            state.assigned.pop(candidate_id, None)
        return self._pending.pop(candidate_id, None) is not None

    def reject(self, candidate_id, evaluator_id, reason):
        """Take back a candidate an evaluator refused, to send it to another one."""
        pending = self._pending.get(candidate_id)
        state = self.evaluators.get(evaluator_id)
        if pending is None or state is None or candidate_id not in state.assigned:
            return False
        del state.assigned[candidate_id]
        pending.rejected_by.add(evaluator_id)
        pending.reasons.append(f'{evaluator_id}: {reason}')
        if not any(candidate_id in other.assigned for other in self.evaluators.values()):
            self._queue.appendleft(candidate_id)
        return True

    def _least_loaded(self, pending, live):
        # the last candidates of a batch go only to evaluators with nothing to do
        first = self._first_attempts.get(pending.candidate.candidate_id, 0)
        last = pending.attempts == first and 1 < len(live) and len(self._queue) <= len(live)
        candidates = [
            (len(state.assigned) / state.capacity, evaluator_id)
            for evaluator_id, state in self.evaluators.items()
            if evaluator_id in live
            and len(state.assigned) < (1 if last else state.capacity)
            and evaluator_id not in pending.rejected_by
            and pending.candidate.candidate_id not in state.assigned
        ]
        return min(candidates)[1] if candidates else None

    def _reclaim_from_silent(self, now):
        for state in self.evaluators.values():
            if now - state.last_heard > self.heartbeat_timeout and state.assigned:
                for candidate_id in sorted(state.assigned, reverse=True):
                    self._queue.appendleft(candidate_id)
                state.assigned.clear()

    def _requeue_overdue(self, now):
        for state in self.evaluators.values():
            for candidate_id, sent_at in list(state.assigned.items()):
                if now - sent_at > self.evaluation_timeout:
                    # keep the old assignment: whichever evaluator answers first wins
                    state.assigned[candidate_id] = float('inf')
                    self._queue.append(candidate_id)
