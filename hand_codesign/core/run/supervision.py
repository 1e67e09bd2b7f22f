"""
The supervision of a run's own processes as events and a clock: when to restart, when to stop.

`hand-codesign run` starts a recorder, N evaluators and the optimizer. Before this module a
recorder that died ended the run, and an evaluator that died while the run waited for its
evaluators left the optimizer "waiting for N evaluator(s)" without end. The Supervisor decides
instead, from the exits it is told of and its clock, and ros/runner.py only starts and stops
processes:

- an evaluator or the recorder that exits while the run goes on is restarted, after a short
  delay that doubles with each exit of the same role within `window` seconds (a process that
  fails at once, e.g. on a broken installation, is not restarted in a tight loop);
- a role that exits more than `max_restarts` times within `window` seconds is given up, and
  with it the run: the run cannot get the evaluators (or the recorder) it needs, says which,
  and stops cleanly (the bag is closed);
- the optimizer must say that its evaluators are there ("evaluators ready") within
  `start_timeout` seconds (0: no limit, for a run that waits for evaluators started by hand);
  otherwise the run says so and stops.

A restarted evaluator serves under a new evaluator id (`evaluator-1-r1`): the optimizer takes
the candidates of the silent old id back and sends them again, as for any evaluator whose
heartbeats stop, and the new process does not redo what the history of the candidates topic
still holds for the old id. Evaluations are pure functions of their candidates, so restarts
change neither the summaries nor the result.
"""

import dataclasses
import time

RECORDER = 'recorder'
FIRST_RESTART_DELAY = 0.25
MAX_RESTART_DELAY = 8.0


def evaluator_role(index):
    """Return the role name of the run's evaluator number index."""
    return f'evaluator-{index}'


def serves_role(evaluator_id, roles):
    """Return whether an evaluator id is that of one of `roles`, started or restarted."""
    role, restart, count = evaluator_id.rpartition('-r')
    return evaluator_id in roles or (bool(restart) and count.isdigit() and role in roles)


@dataclasses.dataclass
class Role:
    """One process the run keeps alive: its exits and its next start."""

    name: str
    starts: int = 0                  # processes started for this role so far
    exits: list = dataclasses.field(default_factory=list)   # clock times of its exits
    restart_at: float = None         # when the next process of this role is due
    last_code: int = None


class Supervisor:
    """Decide restarts and the end of a run from process exits and a clock (module doc)."""

    def __init__(self, evaluators, max_restarts=3, window=60.0, start_timeout=0.0,
                 clock=time.monotonic):
        self.clock = clock
        self.max_restarts = max_restarts
        self.window = window
        self.start_timeout = start_timeout
        self.roles = {name: Role(name) for name in
                      [RECORDER] + [evaluator_role(index) for index in range(evaluators)]}
        self.created = clock()
        self.optimizer_started = False
        self.gave_up = None    # why the run must stop, once it must
        self.restarts = 0

    def started(self, role):
        """Record that a process of role was started; return the evaluator id it serves as."""
        entry = self.roles[role]
        entry.starts += 1
        entry.restart_at = None
        return serving_id(role, entry.starts - 1)

    def exited(self, role, code):
        """Take the exit of role's process; schedule its restart or give the run up."""
        entry = self.roles[role]
        now = self.clock()
        entry.last_code = code
        entry.exits = [t for t in entry.exits if now - t <= self.window] + [now]
        recent = len(entry.exits)
        if recent > self.max_restarts:
            what = 'the recorder' if role == RECORDER else f'evaluator {role}'
            self.give_up(f'{what} exited {recent} times within {self.window:g} s (last exit '
                         f'code {code}): the run cannot get the processes it needs')
            return
        entry.restart_at = now + min(MAX_RESTART_DELAY, FIRST_RESTART_DELAY * 2 ** (recent - 1))
        self.restarts += 1

    def optimizer_ready(self):
        """Take the optimizer's word that its evaluators are there and the run has started."""
        self.optimizer_started = True

    def due(self):
        """Return the roles whose restart is due now; check the start deadline."""
        now = self.clock()
        if (not self.optimizer_started and self.start_timeout > 0
                and now - self.created > self.start_timeout and self.gave_up is None):
            self.give_up(f'the evaluators did not join within {self.start_timeout:g} s '
                         '(--start-timeout)')
        if self.gave_up is not None:
            return []
        return [entry.name for entry in self.roles.values()
                if entry.restart_at is not None and now >= entry.restart_at]

    def give_up(self, reason):
        """Record why the run must stop (the first reason stands)."""
        if self.gave_up is None:
            self.gave_up = reason


def serving_id(role, restart):
    """Return the evaluator id of a role's process: the role, then '-r<k>' after k restarts."""
    return role if restart == 0 else f'{role}-r{restart}'


def node_name(evaluator_id):
    """Return a ROS node name for an evaluator id: letters, digits and '_' only."""
    cleaned = ''.join(c if c.isalnum() else '_' for c in evaluator_id)
    return cleaned if cleaned[:1].isalpha() else f'evaluator_{cleaned}'
