"""
Outcome descriptors: what a design did at the end of its rollouts, averaged over the worlds.

A quality-diversity archive (core.search.quality_diversity) may span outcome descriptors besides
those of the morphology (core.task.descriptors). They are measured in the very rollouts
`core.evaluate.evaluate_design` runs, by reading the scene once at the end of each world's
rollout (its last step, or the goal check where early termination stopped it) before the
object is removed; nothing in the scene changes, so the objectives stay bit-identical:

    limit_rest  the share of the worlds in which some finger has a joint within
                LIMIT_TOLERANCE of one of its limits (or past it: Bullet's limits are soft)
                and the same finger touches the object (a contact point between any segment
                of that finger and the object with a separation of at most CONTACT_DISTANCE)
    touch       the share of the worlds in which any finger touches the object
    turn        the mean over the worlds of the object's turn about the vertical from its start
                pose, as a share of half a turn (|angle| / pi, the angle in [-pi, pi]): a
                capsule turned by 90 degrees either way counts 0.5

A world the design starts in collision with is not simulated and counts as none of them (0);
so does a world whose simulation became unstable (its scene is not a resting state). All are
means over all the candidate's worlds, in [0, 1]. core.experiments.measures applies the same
rule on unseen worlds (`resting_on_limit_touching`).

They are computed only when the task's `optimizer.archive.descriptors` names one
(`task_outcomes`): every other evaluation pays nothing. They travel in the Evaluation message
(`outcome_names`, `outcomes`) and reach the search as an `Answer` (objectives and outcomes).
"""

import dataclasses
import math
from typing import Tuple

from hand_codesign.core.rotations import vertical_turn
import numpy as np

LIMIT_TOLERANCE = 0.02  # rad: a joint this close to a limit (or past it) rests on it
CONTACT_DISTANCE = 0.001  # m: a contact point this close (or penetrating) is a touch
OUTCOME_NAMES = ('limit_rest', 'touch', 'turn')
OUTCOME_RANGE = (0.0, 1.0)  # each outcome descriptor: a mean over the worlds of values in [0, 1]


def task_outcomes(task):
    """Return the outcome descriptors the task's archive names, in its order (else ())."""
    archive = getattr(task, 'archive', None)
    names = archive.descriptors if archive is not None and archive.descriptors else ()
    return tuple(name for name in names if name in OUTCOME_NAMES)


def touching_links(simulator):
    """Return the set of the hand's links that touch the current object."""
    if simulator.object_body is None:
        return set()
    return simulator.touching_links(CONTACT_DISTANCE)


def resting_on_limit_touching(simulator):
    """Return True if some finger has a joint on a limit and touches the current object."""
    return limit_rests(simulator, (on_its_limit,))[0]


def resting_on_reached_limit_touching(simulator):
    """
    Return True if some finger touches the object with a joint on a limit it reached.

    The stricter rule of core.experiments.measures' "joint limits found": the joint rests on a
    limit that its initial angle was not already on (reached_its_limit), so a design that starts a
    joint against a limit and never moves it does not count.
    """
    return limit_rests(simulator, (reached_its_limit,))[0]


def limit_rests(simulator, rules):
    """
    Return, per rule(link, angle), whether a finger touching the object has a joint it holds.

    The scene (contacts, joint angles) is read once for all the rules.
    """
    links = simulator.model.links
    if simulator.object_body is None or not links:
        return tuple(False for _ in rules)
    touching = touching_links(simulator)
    angles = simulator.joint_angles()
    groups = [finger for finger in fingers(links) if touching.intersection(finger)]
    return tuple(any(rule(links[index], angles[index]) for finger in groups for index in finger)
                 for rule in rules)


def fingers(links):
    """Return the link indices of each finger: a finger starts at a link on the palm."""
    groups = []
    for index, link in enumerate(links):
        if link.parent == -1:
            groups.append([])
        groups[-1].append(index)
    return groups


def on_its_limit(link, angle):
    """Return True if a joint's angle is within LIMIT_TOLERANCE of a limit, or past it."""
    if link.lower_limit is None:
        return False
    return (angle <= link.lower_limit + LIMIT_TOLERANCE
            or angle >= link.upper_limit - LIMIT_TOLERANCE)


def reached_its_limit(link, angle):
    """Return True if a joint is on a limit (on_its_limit) that its initial angle was not on."""
    if link.lower_limit is None:
        return False
    start = link.initial_angle
    at_lower = angle <= link.lower_limit + LIMIT_TOLERANCE
    at_upper = angle >= link.upper_limit - LIMIT_TOLERANCE
    return ((at_lower and not start <= link.lower_limit + LIMIT_TOLERANCE)
            or (at_upper and not start >= link.upper_limit - LIMIT_TOLERANCE))


def turn_share(rollout, start):
    """Return the object's turn about the vertical, start to the rollout's end, in half turns."""
    return abs(vertical_turn(start.orientation, rollout.final_orientation)) / math.pi


# each rule reads (simulator, rollout, the world's ObjectState at the start) at a rollout's end
_RULES = {'limit_rest': lambda simulator, rollout, start: float(
              resting_on_limit_touching(simulator)),
          'touch': lambda simulator, rollout, start: float(bool(touching_links(simulator))),
          'turn': lambda simulator, rollout, start: turn_share(rollout, start)}


class OutcomeWatch:
    """Per world, the value of each named outcome at the end of its rollout."""

    def __init__(self, names, starts):
        """
        Watch the rollouts of worlds `starts` for the outcomes `names` (of OUTCOME_NAMES).

        `starts`: each world's object at the start (core.sim.worlds.ObjectState, whose
        orientation `turn` reads), one per world in rollout order.
        """
        self.names = tuple(names)
        self.starts = starts
        self.values = np.zeros((len(starts), len(self.names)))

    def on_end(self, index):
        """Return the Simulator.rollout `on_end` of world `index`, or None without outcomes."""
        if not self.names:
            return None
        start = self.starts[index]

        def read(simulator, rollout):
            # an unstable world's scene is no resting state: it counts as none (0)
            if not rollout.unstable:
                self.values[index] = [_RULES[name](simulator, rollout, start)
                                      for name in self.names]
        return read

    def shares(self):
        """Return the mean over the worlds of each outcome (a share, for the yes-or-no ones)."""
        if not len(self.values):
            return np.zeros(len(self.names))
        return self.values.mean(axis=0)


@dataclasses.dataclass(frozen=True)
class Answer:
    """An evaluation as the search is told it: objectives and the outcome descriptors."""

    objectives: np.ndarray
    outcome_names: Tuple[str, ...] = ()
    outcomes: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))

    @classmethod
    def of(cls, objectives, outcome_names=(), outcomes=()):
        """Return the Answer of message fields (any sequences of numbers and names)."""
        return cls(np.array(objectives, dtype=float), tuple(str(name) for name in outcome_names),
                   np.array(outcomes, dtype=float).reshape(-1))

    def fingerprint(self):
        """Return bytes that two answers share when they agree bit for bit."""
        return b'\0'.join([self.objectives.tobytes(), '\0'.join(self.outcome_names).encode(),
                           self.outcomes.tobytes()])


def objectives_of(value):
    """Return the objective vector of an objective vector, an Answer or an Evaluation."""
    return np.asarray(getattr(value, 'objectives', value), dtype=float)


def outcomes_of(value):
    """Return {outcome name: value} of an Answer or an Evaluation ({} of a bare vector)."""
    return dict(zip(getattr(value, 'outcome_names', ()),
                    (float(v) for v in getattr(value, 'outcomes', ()))))


__all__ = ['Answer', 'CONTACT_DISTANCE', 'LIMIT_TOLERANCE', 'OUTCOME_NAMES', 'OUTCOME_RANGE',
           'OutcomeWatch', 'fingers', 'limit_rests', 'objectives_of', 'on_its_limit',
           'outcomes_of',
           'reached_its_limit', 'resting_on_limit_touching',
           'resting_on_reached_limit_touching', 'task_outcomes', 'touching_links', 'turn_share']
