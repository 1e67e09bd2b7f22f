"""
A raced batch's rounds as the run dispatches them (`worlds: {racing: ...}`; core.search.racing).

With racing, the RunController evaluates a generation in rounds instead of at once: each round
sends the candidates still racing with the round's share of the worlds (Candidate.worlds_from /
worlds_to) as a further attempt of the same candidate id, waits until every one of them is
answered (audits included), and gives the answers to the generation's Race, which stops the
candidates that can no longer be selected. Every decision is taken on a complete round, so a
run gives the same rounds and results with 1, 2 or 8 evaluators, in any order, after any
evaluator dies. An answer to an attempt of an earlier round (a late duplicate) is ignored: the
attempt an Evaluation answers says its round. When the race is done the batch is told with its
RacedAnswers, and the summary records the worlds each candidate met (told_worlds), from which a
resumed run rebuilds the same search.
"""

import dataclasses

from hand_codesign.core.search.racing import Race, RoundAnswer
from hand_codesign.core.sim.objectives import design_torque_penalty
from hand_codesign.core.sim.worlds import world_states
from hand_codesign.core.task.genome import genome_spec
import numpy as np


class RaceRounds:
    """The rounds of one raced batch: what to send, which answers count, what to tell."""

    def __init__(self, batch, task, selected, spec):
        """
        Start the race of `batch` (the search's candidates) on `task` (the batch's task).

        selected: mu of the batch's optimizer (CmaEs.selected); spec: task.worlds.racing.
        """
        self.batch = {candidate.candidate_id: candidate for candidate in batch}
        genome = genome_spec(task)  # (not core.evaluate's: it loads the simulator)
        penalties = {candidate.candidate_id: design_torque_penalty(task,
                                                                   genome.decode(candidate.x))
                     for candidate in batch}
        self.race = Race(list(self.batch), len(world_states(task)), selected, spec,
                         task.objective_weights, penalties)
        self.first_attempts = {}  # candidate id -> its first attempt of the current round
        self.audited = set()

    def units(self, attempts):
        """
        Return the current round's candidates, each with its share of the worlds.

        attempts: candidate id -> dispatches so far; the round's attempts start there.
        """
        share = self.race.share
        self.first_attempts = {candidate_id: attempts.get(candidate_id, 0)
                               for candidate_id in self.race.racing}
        return [dataclasses.replace(self.batch[candidate_id], share=share)
                for candidate_id in self.race.racing]

    def unit(self, candidate_id):
        """Return the candidate as the current round sends it."""
        return dataclasses.replace(self.batch[candidate_id], share=self.race.share)

    def stale(self, candidate_id, attempt):
        """Return whether an answer to `attempt` belongs to an earlier round (or no round)."""
        first = self.first_attempts.get(candidate_id)
        return first is None or int(attempt) < first

    @staticmethod
    def answer(objectives, evaluation):
        """Return the RoundAnswer of an Evaluation (any object with its fields)."""
        objectives = np.asarray(objectives, dtype=float)
        world = np.asarray(evaluation.world_objectives, dtype=float)
        return RoundAnswer(objectives, world.reshape(-1, len(objectives)),
                           bool(evaluation.collision))

    def finish_round(self, results, audited):
        """
        Give the round's answers (id -> RoundAnswer) to the race; return whether it is done.

        audited: the candidates audited in the round (for the batch's summary).
        """
        self.audited |= set(audited)
        self.race.told(results)
        self.first_attempts = {}
        return self.race.done

    def answers(self):
        """Return id -> RacedAnswer of the batch, once the race is done."""
        return self.race.answers()
