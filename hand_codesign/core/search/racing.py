"""
Racing over the worlds (`worlds: {racing: ...}`, not in the paper): fewer wasted rollouts.

CMA-ES updates its distribution from the mu best of a generation's lambda candidates (the best
half, the only ranks with a positive weight); a candidate whose first worlds already rank it
far below them spends its remaining worlds for nothing. After Heidrich-Meisner and Igel
(ICML 2009, "Hoeffding and Bernstein races for selecting policies in evolutionary direct
policy search"), a generation's worlds are evaluated in rounds of about equal shares (the
same worlds in the same order for every candidate, `round_bounds`), and after each round a
candidate stops once it can no longer be among the mu selected:

- its fitness so far, f_i = sum_o w_o (mean of h_o over the m worlds it met) + its torque
  penalty, is within `serfling_radius` (eps) of the fitness over all n worlds: the worlds are
  independent draws, so the m met first are a sample without replacement of the n, and by
  Hoeffding's inequality with Serfling's correction for sampling without replacement
  (Serfling 1974, "Probability inequalities for the sum in sampling without replacement";
  the factor rho_m of Bardenet and Maillard 2015, Bernoulli 21(3)) the two means differ by
  more than eps = R sqrt(rho_m ln(2 / delta') / (2 m)) with probability at most delta', where
  R is the stated width of a world's weighted objectives (`range`) and
  rho_m = min(1 - (m - 1) / n, (1 - m / n)(1 + 1 / m)), 0 once every world is met;
- candidate i stops when at least mu others are certainly better: f_j + eps < f_i - eps.
  delta' = delta / (lambda (rounds - 1)) covers every candidate at every decision at once, so
  with probability 1 - delta no candidate that stops would have been among the mu best.

What the bound states: a world's weighted objectives lie in a band R wide. Every candidate
meets the same worlds, so what the candidates of a generation share on a world (its baseline,
e.g. an untouched box's error, which the world's randomized start sets) cancels out of every
comparison the rule makes: the rule is the same for the values minus any per-world baseline,
and R need only bound those (bench/bench_racing.py measures both spans: about 0.05 raw and a
median of 0.01 about each world's median on Tasks 5 and 6). A world outside the band (an
unstable world counts 10,000 per objective) breaks the statement for its candidate, if it is
one it has not met yet; its true rank is then lower than the race assumed, which can wrongly
stop others only if it was one of the mu counted as better.

What it saves: a candidate stops only once at least mu others lead it by 2 eps, about R at
the first of four rounds of 64 worlds, 0.3 R at the last; within a CMA-ES generation the
candidates' means lie closer than the worlds' spread, so on the first generations of Tasks 5
and 6 the replayed race saves 0 to 3 % of the rollouts, more the narrower the stated band
(bench/bench_racing.py), and stopped none of the mu best.

A candidate that starts in collision is known at once: every round checks the starts of all the
worlds (core.evaluate's `share`), so its first round gives its exact objectives
(COLLISION_PENALTY) and it races no further. A candidate that met all the worlds is told its
objectives exactly as an evaluation on all of them gives them, bit for bit (`combine_worlds`
of the same per-world values); one that stopped early is told the mean over the worlds it met
(eq. 5 over those), as a RacedAnswer with complete=False: CMA-ES ranks it after every complete
one and runs without negative weights (core.search.optimizers.CmaEs, raced), so its update
uses only ranks that are known.
"""

import dataclasses
import math

from hand_codesign.core.sim.objectives import combine_worlds
import numpy as np


def round_bounds(worlds, rounds):
    """Return the world indices where the rounds start and end: (0, ..., worlds), increasing."""
    count = max(1, min(int(rounds), int(worlds)))
    return tuple(worlds * index // count for index in range(count + 1))


def serfling_radius(seen, worlds, value_range, delta):
    """
    Return eps: the mean of `worlds` values within eps of the mean of the `seen` met first.

    Holds with probability 1 - delta for values in a band `value_range` wide (see the module
    doc); 0 once every world is met.
    """
    if seen >= worlds:
        return 0.0
    rho = min(1.0 - (seen - 1) / worlds, (1.0 - seen / worlds) * (1.0 + 1.0 / seen))
    return value_range * math.sqrt(rho * math.log(2.0 / delta) / (2.0 * seen))


@dataclasses.dataclass(frozen=True)
class RoundAnswer:
    """A candidate's evaluation in one round: its share of the worlds and the start check."""

    objectives: np.ndarray        # over the round's worlds, with the torque penalty
    world_objectives: np.ndarray  # (round's worlds, objectives): h_o of each world
    collision: bool               # the design starts in collision in one of all the worlds

    def fingerprint(self):
        """Return the bytes two agreeing answers share (core.run.audits compares them)."""
        return (np.asarray(self.objectives, dtype=float).tobytes()
                + np.asarray(self.world_objectives, dtype=float).tobytes()
                + bytes([bool(self.collision)]))


@dataclasses.dataclass(frozen=True)
class RacedAnswer:
    """What a raced candidate is told: objectives over the worlds it met, and how many."""

    objectives: np.ndarray
    worlds: int             # worlds it met (all of them when it collided at the start)
    complete: bool = True   # False: stopped early, its objectives the mean of a share


class Race:
    """One generation's race (see the module doc): which candidates meet which worlds."""

    def __init__(self, candidate_ids, worlds, selected, spec, weights, penalties):
        """
        Start the race of a generation.

        candidate_ids: the generation's ids; worlds: its worlds n; selected: mu, the ranks
        CMA-ES selects; spec: the task's core.task.parts.RacingSpec; weights: the objective
        weights (objectives,); penalties: candidate id -> its torque penalty (eq. 2, added to
        every objective).
        """
        self.ids = tuple(int(candidate_id) for candidate_id in candidate_ids)
        self.worlds, self.selected, self.spec = int(worlds), int(selected), spec
        self.weights = np.asarray(weights, dtype=float)
        self.penalties = dict(penalties)
        self.bounds = round_bounds(self.worlds, spec.rounds)
        self.round = 0
        decisions = max(1, len(self.bounds) - 2)
        self.delta = spec.delta / (len(self.ids) * decisions)
        self._rows = {candidate_id: [] for candidate_id in self.ids}
        self.collided, self.stopped = set(), set()

    @property
    def share(self):
        """Return (first, end): the worlds of the current round."""
        return self.bounds[self.round], self.bounds[self.round + 1]

    @property
    def racing(self):
        """Return the ids that meet the current round's worlds, in the generation's order."""
        if self.done:
            return []
        return [candidate_id for candidate_id in self.ids
                if candidate_id not in self.collided and candidate_id not in self.stopped]

    @property
    def done(self):
        """Return whether every candidate's answer is known."""
        return self.round >= len(self.bounds) - 1 or not any(
            candidate_id not in self.collided and candidate_id not in self.stopped
            for candidate_id in self.ids)

    def told(self, answers):
        """Take the current round's RoundAnswers (id -> answer) of every racing candidate."""
        racing = self.racing
        missing = sorted(set(racing) - set(answers))
        if missing:
            raise ValueError(f'round {self.round}: no answers for candidates {missing}')
        for candidate_id in racing:
            answer = answers[candidate_id]
            if answer.collision:
                self.collided.add(candidate_id)
            self._rows[candidate_id].append(np.asarray(answer.world_objectives, dtype=float))
        self.round += 1
        if not self.done:
            self.stopped |= set(self.losers())

    def fitness(self, candidate_id):
        """Return the weighted fitness over the worlds met so far (exact once complete)."""
        return float(np.dot(self.weights, self._objectives(candidate_id)))

    def losers(self):
        """Return the racing ids that at least mu others certainly beat, by the bound."""
        seen = self.bounds[self.round]
        radius = serfling_radius(seen, self.worlds, self.spec.value_range, self.delta)
        racing = self.racing
        known = racing + sorted(self.collided)
        upper = np.array([self.fitness(candidate_id)
                          + (radius if candidate_id in racing else 0.0)
                          for candidate_id in known])
        losers = []
        for candidate_id in racing:
            lower = self.fitness(candidate_id) - radius
            if np.count_nonzero(upper < lower) >= self.selected:
                losers.append(candidate_id)
        return losers

    def _objectives(self, candidate_id):
        rows = self._rows[candidate_id]
        values = np.concatenate(rows, axis=0) if rows else np.zeros((0, len(self.weights)))
        if candidate_id in self.collided:
            return combine_worlds(np.zeros((self.worlds, len(self.weights))), collision=True)
        return combine_worlds(values, self.penalties.get(candidate_id, 0.0))

    def answers(self):
        """Return id -> RacedAnswer of every candidate, once the race is done."""
        if not self.done:
            raise ValueError(f'the race is in round {self.round}: answers come at its end')
        result = {}
        for candidate_id in self.ids:
            met = sum(len(rows) for rows in self._rows[candidate_id])
            complete = candidate_id in self.collided or met == self.worlds
            result[candidate_id] = RacedAnswer(self._objectives(candidate_id),
                                               self.worlds if complete else met, complete)
        return result

    def rollouts_saved(self):
        """Return the worlds the stopped candidates did not meet."""
        return sum(self.worlds - sum(len(rows) for rows in self._rows[candidate_id])
                   for candidate_id in self.stopped)
