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

The bottom-up path (`bottom_up_path`) starts at a configurable structure and repeatedly goes to
an unvisited neighbour that grows the hand: more joints, or as many joints on more fingers. The
paper's path keeps the degrees of freedom and the number of optimized parameters increasing and
prefers rearranging joints to adding new ones; so among the growing neighbours the path takes

1. a move (it keeps the number of joints, i.e. actuators, and adds only the new finger's
   placement on the palm),
2. else adding a joint to an existing finger (fewer new parameters than a new finger),
3. else adding a finger,

and among equals the most balanced structure (smallest longest finger: (2, 2) before (1, 3)),
then the smallest tuple. Moves between existing fingers ((1, 3) -> (2, 2)) never grow the
hand, so the path never takes them. Within at most 2 fingers of at most 3 joints, from (1,)::

    (1,) -> (2,) -> (1, 1) -> (1, 2) -> (2, 2) -> (2, 3) -> (3, 3)

and within 3 fingers of 3 joints::

    (1,) -> (2,) -> (1, 1) -> (1, 2) -> (1, 1, 1) -> (1, 1, 2) -> (1, 2, 2) -> (2, 2, 2)
         -> (2, 2, 3) -> (2, 3, 3) -> (3, 3, 3)

The task's `hierarchy.stop_structure` ends the path and bounds it: at most as many fingers, and
joints per finger, as the stop structure has (and as max_fingers / max_joints allow). Task 4
("stops when reaching a two-fingered hand with three joints", stop structure (2, 3)) thus runs
the first path above, six structures.

`HierarchySearch` runs one optimization per structure on that path and, after each, evaluates
the structure's best design on the task's evaluation world states; it stops as soon as every
position objective is within `hierarchy.position_threshold` and every orientation objective
within `hierarchy.orientation_threshold` (each averaged over those worlds, as in equation 5).
It is driven with ask/tell like an optimizer, so the ROS optimizer node drives it one batch at a
time; `run_hierarchy` drives it with any callable that evaluates a batch.
"""

import dataclasses
import pickle
from typing import Optional, Tuple

from hand_codesign.core.genome import genome_spec
from hand_codesign.core.optimizers import (
    Candidate, make_optimizer, OptimizerError, OptimizerResult, STATE_FORMAT, TellError)
import numpy as np

Structure = Tuple[int, ...]

MAX_FINGERS = 3
MAX_JOINTS = 3

# Preference of the transitions on the bottom-up path (lower first).
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
    there. Without `stop` it ends where no neighbour grows the hand. Raise HierarchyError when
    `stop` is not on the path.
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
        growing = [(neighbour, kind) for neighbour, kind in
                   transitions(current, max_fingers, max_joints).items()
                   if hierarchy_level(neighbour) > hierarchy_level(current)
                   and neighbour not in path]
        if not growing:
            break
        growing.sort(key=lambda item: (_PREFERENCE[item[1]], max(item[0]), item[0]))
        path.append(growing[0][0])
    if stop is not None and path[-1] != stop:
        raise HierarchyError(
            f'stop structure {list(stop)} is not on the bottom-up path from {list(start)} within '
            f'{max_fingers} fingers of {max_joints} joints: {[list(s) for s in path]}')
    return path


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
    result: OptimizerResult  # the optimizer's best design
    stop_reason: dict  # why the structure's optimization stopped
    check_id: int  # candidate id of the check evaluation
    check_objectives: np.ndarray  # objectives of the best design on the evaluation worlds
    check_fitness: float
    goals_met: bool


class HierarchySearch:
    """
    One optimization per structure along the bottom-up path, with the paper's stop rule.

    Use like an optimizer: `ask()` returns the candidates to evaluate (each with its
    `structure`), to be evaluated with `evaluation_task` (the task replaced with the current
    structure; for the check of a structure's best design, also with the evaluation world
    states); `tell()` takes id -> objectives; `stop()` says why the search ended.
    Candidate ids run on across structures. The state pickles (`get_state` / `from_state`).
    """

    def __init__(self, task, path=None, first_id=0, genome_size=None):
        """
        Prepare the search of `task` (with a `hierarchy` section unless `path` is given).

        genome_size(task) -> int gives the genome length of a structure (default: the size of
        core.genome's GenomeSpec).
        """
        hierarchy = task.hierarchy
        if hierarchy is None:
            raise HierarchyError(f'task {task.name!r} ({task.source}) has no hierarchy section')
        self.task = task
        if path is None:
            path = bottom_up_path(hierarchy.start, hierarchy.stop_structure,
                                  hierarchy.max_fingers, hierarchy.max_joints)
        self.path = [normalize_structure(structure) for structure in path]
        self.position_threshold = hierarchy.position_threshold
        self.orientation_threshold = hierarchy.orientation_threshold
        self.evaluation_world_states = hierarchy.evaluation_world_states
        self._genome_size = genome_size
        self._index = 0
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
            return self.structure_task.replace(num_world_states=self.evaluation_world_states)
        return self.structure_task

    @property
    def checking(self):
        """Return True while the candidate asked is the check of a structure's best design."""
        return self._check is not None

    @property
    def optimizer(self):
        """Return the optimizer of the current structure."""
        return self._optimizer

    def ask(self):
        """Return the candidates to evaluate next (the same ones again until told)."""
        if self._stop:
            return []
        if self._check is not None:
            return [self._check]
        return [dataclasses.replace(candidate, structure=self.structure)
                for candidate in self._optimizer.ask()]

    def tell(self, results):
        """Tell the evaluations (id -> objectives) of the candidates asked."""
        if self._stop:
            raise TellError(f'the hierarchy search has stopped ({self._stop}); nothing to tell')
        if self._check is None:
            self._optimizer.tell(results)
            if self._optimizer.stop():
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
        return make_optimizer(task, size, first_id=first_id)

    def _ask_check(self):
        result = self._optimizer.result
        self._check = Candidate(self._optimizer.next_id, self._optimizer.generation, result.x,
                                self.structure)

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
            self.structure, self._optimizer.result, self._optimizer.stop(), check_id,
            objectives, self._optimizer.fitness_of(objectives), met))
        self._check = None
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
    'all_structures', 'bottom_up_path', 'evaluate_candidates', 'goals_within', 'HierarchyError',
    'HierarchySearch', 'hierarchy_level', 'normalize_structure', 'run_hierarchy',
    'StructureOutcome', 'transitions',
]
