"""
The hand-structure hierarchy of Fig. 1 and the bottom-up search along it (section III.B).

A structure is the number of hinge joints per finger, written as a sorted tuple: (1,) is one
finger with one joint, (1, 2) two fingers with one and two joints. The fingers of a structure
are interchangeable at this level (their placement is optimized), so (2, 1) is (1, 2).

Transitions (the edges of Fig. 1) change a structure by one joint with its segment:

- add a joint: one finger gets one more joint ((1, 1) -> (1, 2));
- add a finger: a new finger with one joint ((1, 1) -> (1, 1, 1));
- remove a joint or a finger: the inverse of the two above;
- move a joint: one joint leaves its finger for another or for a new finger
  ((2,) -> (1, 1), (1, 2) -> (1, 1, 1), (1, 3) -> (2, 2)); a finger left without joints
  disappears.

The bottom-up path (`bottom_up_path`) starts at a configurable structure and walks Fig. 1's
edges, never back to a structure it visited. The paper's text prefers rearranging joints to
adding new ones and compares structures of as many joints ((2, 2) and (1, 3) in Fig. 3); Fig. 1
draws only growing edges. Both hold here: from each structure the path takes

1. a move of a joint (the same number of joints, i.e. actuators), while one leads to an
   unvisited structure,
2. else adding a joint to a finger (the degrees of freedom grow; fewer new parameters than a
   new finger),
3. else adding a finger,

and among equals the most balanced structure (smallest longest finger), then the smallest
tuple. So from each structure every move to an unvisited structure is tried before the hand
grows. The task's `hierarchy.stop_structure` ends the path and bounds it: at most as many
fingers, and joints per finger, as the stop structure has (and as max_fingers / max_joints
allow). Task 4 ("stops when reaching a two-fingered hand with three joints", stop structure
(2, 3))::

    (1,) -> (2,) -> (1, 1) -> (1, 2) -> (3,) -> (1, 3) -> (2, 2) -> (2, 3)

Without a stop structure the path ends where no unvisited neighbour is left.

Three-finger hands (Fig. 3) are grown from the best two-finger hands: when a task gives
`max_fingers` above the stop structure's fingers, the path is followed by a finger of one joint
added to each of the `GROWN_FROM` (2) structures of the most fingers on the path whose checks
scored best (lowest weighted sum, the earlier on ties): for Task 4 e.g. (1, 3) -> (1, 1, 3) and
(2, 2) -> (1, 2, 2). Which ones is decided from the told objectives only, so replaying them
(resume, analysis) re-derives it.

`HierarchySearch` optimizes each structure `REPEATS` (2) times one after the other, as the paper
does, each optimization with the task's budget and its own seed `derived_seed(run seed,
structure index, repeat)`; the structure's best design is the better of the two (lowest
weighted sum on the training worlds, the first on ties). That design is then checked on
`hierarchy.evaluation_world_states` held-out worlds (core.sim.worlds: another stream of the run's
seed, disjoint from the training worlds). The search stops as soon as every position objective
of a check is within `hierarchy.position_threshold` and every orientation objective within
`hierarchy.orientation_threshold` (each averaged over those worlds, as in equation 5). It is
driven with ask/tell like an optimizer, so the ROS optimizer node drives it one batch at a time;
`run_hierarchy` drives it with any callable that evaluates a batch.
"""

import dataclasses
import pickle
from typing import Optional, Tuple

from hand_codesign.core.search.factory import make_optimizer
from hand_codesign.core.search.optimizers import (Candidate, derived_seed, OptimizerError,
                                                  OptimizerResult, STATE_FORMAT, TellError)
from hand_codesign.core.task.genome import genome_spec
from hand_codesign.core.task.variant import Variant
import numpy as np

Structure = Tuple[int, ...]

MAX_FINGERS = 3
MAX_JOINTS = 3

REPEATS = 2  # optimizations of each structure, each with its own seed
GROWN_FROM = 2  # best structures of the path a finger is added to

# Preference of the transitions on the bottom-up path (lower first); others are not taken.
_PREFERENCE = {'move joint': 0, 'add joint': 1, 'add finger': 2}


class HierarchyError(ValueError):
    """A structure or hierarchy setting that cannot be used."""


def normalize_structure(structure) -> Structure:
    """Return the structure as a sorted tuple of positive joint counts."""
    try:
        joints = tuple(sorted(int(count) for count in structure))
    except (TypeError, ValueError):
        raise HierarchyError(
            f'a structure is a list of joints per finger, e.g. [1, 2]; got {structure!r}'
        ) from None
    if not joints or joints[0] < 1:
        raise HierarchyError(f'a structure needs at least one finger with at least one joint; '
                             f'got {structure!r}')
    return joints


def hierarchy_level(structure) -> Tuple[int, int]:
    """Return (joints, fingers): the hand grows when this increases."""
    return (sum(structure), len(structure))


def _sort_key(structure):
    return hierarchy_level(structure) + (max(structure), structure)


def all_structures(max_fingers=MAX_FINGERS, max_joints=MAX_JOINTS):
    """
    Return every structure of Fig. 1 up to the limits, level by level.

    Ordered by joints, then fingers, then the most balanced, then the tuple: (1,), (2,),
    (1, 1), (3,), (1, 2), (1, 1, 1), (2, 2), (1, 3), (1, 1, 2), (2, 3), ...
    """
    structures = set()

    def extend(prefix):
        if prefix:
            structures.add(tuple(prefix))
        if len(prefix) < max_fingers:
            for joints in range(prefix[-1] if prefix else 1, max_joints + 1):
                extend(prefix + [joints])

    extend([])
    return sorted(structures, key=_sort_key)


def transitions(structure, max_fingers=MAX_FINGERS, max_joints=MAX_JOINTS):
    """Return {neighbour structure: kind} of one transition from `structure` within limits."""
    structure = normalize_structure(structure)
    found = {}

    def offer(joints, kind):
        if joints and len(joints) <= max_fingers and max(joints) <= max_joints:
            neighbour = tuple(sorted(joints))
            if neighbour != structure and neighbour not in found:
                found[neighbour] = kind

    fingers = list(structure)
    for index, count in enumerate(fingers):
        offer(fingers[:index] + [count + 1] + fingers[index + 1:], 'add joint')
        if count > 1:
            offer(fingers[:index] + [count - 1] + fingers[index + 1:], 'remove joint')
        elif len(fingers) > 1:
            offer(fingers[:index] + fingers[index + 1:], 'remove finger')
    offer(fingers + [1], 'add finger')
    for source, count in enumerate(fingers):
        rest = fingers[:source] + ([count - 1] if count > 1 else []) + fingers[source + 1:]
        # The joint moves onto another finger or starts a new finger.
        for target in range(len(rest)):
            offer(rest[:target] + [rest[target] + 1] + rest[target + 1:], 'move joint')
        offer(rest + [1], 'move joint')
    return found


def bottom_up_path(start=(1,), stop=None, max_fingers=None, max_joints=None):
    """
    Return the bottom-up sequence of structures from `start` (see the module docstring).

    The path stays within max_fingers fingers of max_joints joints (default 3 and 3) and, with
    a `stop` structure, within its number of fingers and its longest finger, so that it ends
    there. Without `stop` it ends where no move or addition leads to an unvisited structure.
    Raise HierarchyError when `stop` is not on the path.
    """
    start = normalize_structure(start)
    stop = None if stop is None else normalize_structure(stop)
    max_fingers = MAX_FINGERS if max_fingers is None else max_fingers
    max_joints = MAX_JOINTS if max_joints is None else max_joints
    if stop is not None:
        max_fingers, max_joints = min(max_fingers, len(stop)), min(max_joints, max(stop))
    if len(start) > max_fingers or max(start) > max_joints:
        raise HierarchyError(f'start structure {list(start)} exceeds {max_fingers} fingers of '
                             f'{max_joints} joints')
    path = [start]
    while path[-1] != stop:
        current = path[-1]
        steps = [(neighbour, kind) for neighbour, kind in
                 transitions(current, max_fingers, max_joints).items()
                 if kind in _PREFERENCE and neighbour not in path]
        if not steps:
            break
        steps.sort(key=lambda item: (_PREFERENCE[item[1]], max(item[0]), item[0]))
        path.append(steps[0][0])
    if stop is not None and path[-1] != stop:
        raise HierarchyError(
            f'stop structure {list(stop)} is not on the bottom-up path from {list(start)} within '
            f'{max_fingers} fingers of {max_joints} joints: {[list(s) for s in path]}')
    return path


def grows_fingers(hierarchy):
    """Return True when a hierarchy grows fingers after its path (max_fingers above stop's)."""
    return (hierarchy.stop_structure is not None and hierarchy.max_fingers is not None
            and hierarchy.max_fingers > len(hierarchy.stop_structure))


def grown_choices(path, max_joints=None):
    """Return every structure the hierarchy may grow from `path` (a finger of one joint)."""
    max_joints = MAX_JOINTS if max_joints is None else max_joints
    most = max(len(structure) for structure in path)
    choices = []
    for structure in path:
        grown = normalize_structure(structure + (1,))
        if len(structure) == most and max(grown) <= max_joints and grown not in path + choices:
            choices.append(grown)
    return choices


def goals_within(objective_names, objectives, position_threshold, orientation_threshold):
    """Return True when every position and orientation objective is within its threshold."""
    for name, value in zip(objective_names, objectives):
        threshold = position_threshold if name.startswith('position') else orientation_threshold
        if not value <= threshold:
            return False
    return True


@dataclasses.dataclass(frozen=True)
class StructureOutcome:
    """One structure's optimization and the check of its best design."""

    structure: Structure
    result: OptimizerResult  # the better of the optimizations' best designs
    stop_reason: dict  # why the structure's last optimization stopped
    check_id: int  # candidate id of the check evaluation
    check_objectives: np.ndarray  # objectives of the best design on the held-out worlds
    check_fitness: float
    goals_met: bool
    results: Tuple[OptimizerResult, ...] = ()  # each optimization's best design, in order
    seeds: Tuple[int, ...] = ()  # each optimization's seed, in order


class HierarchySearch:
    """
    One optimization per structure along the bottom-up path, with the paper's stop rule.

    Use like an optimizer: `ask()` returns the candidates to evaluate (each with its
    `structure`), to be evaluated with `evaluation_task` (the task replaced with the current
    structure; for the check of a structure's best design, also with the evaluation world
    states, held out); `tell()` takes id -> objectives; `stop()` says why the search ended.
    Candidate ids run on across structures and repeats. The state pickles (`get_state` /
    `from_state`).
    """

    def __init__(self, task, path=None, first_id=0, genome_size=None):
        """
        Prepare the search of `task` (with a `hierarchy` section unless `path` is given).

        genome_size(task) -> int gives the genome length of a structure (default: the size of
        core.task.genome's GenomeSpec). A given `path` is visited as it is, without grown
        structures.
        """
        hierarchy = task.hierarchy
        if hierarchy is None:
            raise HierarchyError(f'task {task.name!r} ({task.source}) has no hierarchy section')
        self.task = task
        self._grow = path is None and grows_fingers(hierarchy)
        if path is None:
            path = bottom_up_path(hierarchy.start, hierarchy.stop_structure,
                                  hierarchy.max_fingers, hierarchy.max_joints)
        self.path = [normalize_structure(structure) for structure in path]
        self.position_threshold = hierarchy.position_threshold
        self.orientation_threshold = hierarchy.orientation_threshold
        self.evaluation_world_states = hierarchy.evaluation_world_states
        self._genome_size = genome_size
        self._index = 0
        self._repeat = 0
        self._results = []  # best designs of the current structure's finished optimizations
        self._seeds = []
        self._outcomes = []
        self._check = None  # the pending check Candidate
        self._stop = {}
        self._optimizer = self._start_optimizer(first_id)

    # -- driving ------------------------------------------------------------------------------

    @property
    def structure(self):
        """Return the structure being optimized (or checked)."""
        return self.path[self._index]

    @property
    def structure_task(self):
        """Return the task of the current structure."""
        return self.task.replace(structure=self.structure)

    @property
    def evaluation_task(self):
        """Return the task with which the candidates of `ask()` must be evaluated."""
        if self._check is not None:
            return self.structure_task.replace(num_world_states=self.evaluation_world_states,
                                               held_out=True)
        return self.structure_task

    @property
    def checking(self):
        """Return True while the candidate asked is the check of a structure's best design."""
        return self._check is not None

    @property
    def optimizer(self):
        """Return the optimizer of the current structure's current optimization."""
        return self._optimizer

    @property
    def repeat(self):
        """Return which optimization of the current structure runs (0, 1, ...)."""
        return self._repeat

    def ask(self):
        """Return the candidates to evaluate next (the same ones again until told)."""
        if self._stop:
            return []
        if self._check is not None:
            return [self._check]
        return [dataclasses.replace(candidate, variant=Variant(structure=self.structure))
                for candidate in self._optimizer.ask()]

    def tell(self, results):
        """Tell the evaluations (id -> objectives) of the candidates asked."""
        if self._stop:
            raise TellError(f'the hierarchy search has stopped ({self._stop}); nothing to tell')
        if self._check is None:
            self._optimizer.tell(results)
            if self._optimizer.stop():
                self._results.append(self._optimizer.result)
                if len(self._results) < REPEATS:
                    self._repeat += 1
                    self._optimizer = self._start_optimizer(self._optimizer.next_id)
                else:
                    self._ask_check()
            return
        self._tell_check(results)

    def stop(self):
        """Return why the search stopped, as a dict; empty while it runs."""
        return dict(self._stop)

    @property
    def outcomes(self):
        """Return the StructureOutcome of every structure done, in order."""
        return list(self._outcomes)

    @property
    def result(self):
        """
        Return the final StructureOutcome, or None before the first structure is done.

        That is the structure that met the thresholds; otherwise the one whose check has the
        lowest weighted sum (the earliest on ties).
        """
        if not self._outcomes:
            return None
        met = [outcome for outcome in self._outcomes if outcome.goals_met]
        if met:
            return met[0]
        return min(self._outcomes, key=lambda outcome: outcome.check_fitness)

    @property
    def next_id(self):
        """Return the id the next new candidate will get."""
        if self._check is not None:
            return self._check.candidate_id + 1
        return self._optimizer.next_id

    # -- saving and restoring ---------------------------------------------------------------

    def get_state(self):
        """Return the whole state as bytes; `from_state` continues from it bit-identically."""
        return pickle.dumps({'format': STATE_FORMAT, 'hierarchy': self},
                            protocol=pickle.HIGHEST_PROTOCOL)

    @staticmethod
    def from_state(state):
        """Return the HierarchySearch saved by `get_state`."""
        try:
            saved = pickle.loads(state)
        except (pickle.UnpicklingError, EOFError, AttributeError, ImportError, TypeError) as exc:
            raise OptimizerError(f'hierarchy state cannot be read: {exc}') from exc
        if not isinstance(saved, dict) or saved.get('format') != STATE_FORMAT or \
                not isinstance(saved.get('hierarchy'), HierarchySearch):
            raise OptimizerError('hierarchy state is not a saved HierarchySearch of format '
                                 f'{STATE_FORMAT}')
        return saved['hierarchy']

    # -- internals --------------------------------------------------------------------------

    def _start_optimizer(self, first_id):
        task = self.structure_task
        size = self._genome_size(task) if self._genome_size else genome_spec(task).size
        seed = derived_seed(self.task.seed, self._index, self._repeat)
        self._seeds.append(seed)
        return make_optimizer(task, size, first_id=first_id, seed=seed)

    def _best_result(self):
        return min(self._results, key=lambda result: result.fitness)  # the first on ties

    def _ask_check(self):
        result = self._best_result()
        self._check = Candidate(self._optimizer.next_id, self._optimizer.generation, result.x,
                                Variant(structure=self.structure))

    def _grown(self):
        """Return the structures grown from the best outcomes of the most fingers (module doc)."""
        hierarchy = self.task.hierarchy
        most = max(len(outcome.structure) for outcome in self._outcomes)
        ranked = sorted((outcome for outcome in self._outcomes
                         if len(outcome.structure) == most),
                        key=lambda outcome: outcome.check_fitness)  # stable: earlier on ties
        max_joints = MAX_JOINTS if hierarchy.max_joints is None else hierarchy.max_joints
        grown = []
        for outcome in ranked[:GROWN_FROM]:
            structure = normalize_structure(outcome.structure + (1,))
            if max(structure) <= max_joints and structure not in self.path + grown:
                grown.append(structure)
        return grown

    def _tell_check(self, results):
        check_id = self._check.candidate_id
        pairs = list(results.items()) if hasattr(results, 'items') else list(results)
        ids = [int(key) for key, _ in pairs]
        if ids != [check_id]:
            raise TellError(
                f'tell() refused: the check of structure {list(self.structure)} expects exactly '
                f'id {check_id}, got ids {ids}',
                missing=[] if check_id in ids else [check_id],
                unknown=[i for i in ids if i != check_id],
                duplicated=[check_id] if ids.count(check_id) > 1 else [])
        values = getattr(pairs[0][1], 'objectives', pairs[0][1])
        objectives = np.array(values, dtype=float).reshape(-1)
        if objectives.shape != (self._optimizer.num_objectives,) or \
                not np.all(np.isfinite(objectives)):
            raise TellError(f'tell() refused: id {check_id} needs '
                            f'{self._optimizer.num_objectives} finite objective values',
                            invalid=[check_id])
        met = goals_within(self.task.objective_names, objectives, self.position_threshold,
                           self.orientation_threshold)
        self._outcomes.append(StructureOutcome(
            self.structure, self._best_result(), self._optimizer.stop(), check_id,
            objectives, self._optimizer.fitness_of(objectives), met, tuple(self._results),
            tuple(self._seeds)))
        self._check = None
        self._results, self._seeds, self._repeat = [], [], 0
        if not met and self._grow and self._index + 1 >= len(self.path):
            self._grow = False
            self.path = self.path + self._grown()
        if met:
            self._stop = {'goals_met': self.structure}
        elif self._index + 1 >= len(self.path):
            self._stop = {'path_end': self.structure}
        else:
            self._index += 1
            self._optimizer = self._start_optimizer(check_id + 1)


def run_hierarchy(task, evaluate_batch, search: Optional[HierarchySearch] = None):
    """
    Run (or continue) a hierarchy search; return the HierarchySearch.

    evaluate_batch(task, candidates) -> {candidate_id: objectives} evaluates a batch with the
    given task (e.g. `evaluate_candidates`, or an evaluator pool).
    """
    search = HierarchySearch(task) if search is None else search
    while not search.stop():
        candidates = search.ask()
        search.tell(evaluate_batch(search.evaluation_task, candidates))
    return search


def evaluate_candidates(task, candidates):
    """Evaluate candidates one after the other with core.evaluate; return id -> objectives."""
    from hand_codesign.core.evaluate import evaluate  # imports the simulator only when needed
    return {candidate.candidate_id: evaluate(candidate.x, task).objectives
            for candidate in candidates}


__all__ = [
    'all_structures', 'bottom_up_path', 'evaluate_candidates', 'goals_within', 'GROWN_FROM',
    'grown_choices', 'grows_fingers', 'HierarchyError', 'REPEATS',
    'HierarchySearch', 'hierarchy_level', 'normalize_structure', 'run_hierarchy',
    'StructureOutcome', 'transitions',
]
