"""
Ask/tell optimizers of the co-design: CMA-ES (pycma) and MO-CMA-ES (DEAP).

CMA-ES with restarts (IPOP, BIPOP) builds on CmaEs in `core.search.restarts`, quality-diversity
search (CMA-MAE, CMA-ME, with pyribs) on AskTellOptimizer in `core.search.quality_diversity`;
`core.search.factory.make_optimizer`, above all three, returns any of them by name.

Both search the normalized genome space (sections III.C and III.D of the paper): the search
starts at the centre of the bounds (0.5 per coordinate) or at a seeded design, with step size
0.1; the space is unbounded because `hand_codesign.core` folds every value back into [0, 1].

The interface follows pycma's ask/tell contract, with ids so that evaluations may come back
from many evaluators in any order::

    optimizer = make_optimizer(task, dim=genome_spec(task).size)
    while not optimizer.stop():
        candidates = optimizer.ask()           # [Candidate(candidate_id, generation, x)]
        optimizer.tell({c.candidate_id: evaluate(c.x, task).objectives for c in candidates})
    optimizer.result                           # best design (and Pareto front for MO-CMA-ES)

Every draw comes from the optimizer's own seed. pycma and DEAP draw from numpy's global
generator (DEAP also may use `random`), so each call into them runs with the optimizer's private
generator states swapped in and the caller's restored afterwards: optimizers are deterministic
and neither disturb nor depend on other code. Do not drive two optimizers from two threads at
once.

The whole state pickles (`get_state` / `from_state`) and continues bit-identically, also in
another process; `replay` rebuilds a run from its recorded evaluations.
"""

import contextlib
import dataclasses
import pickle
import random
from typing import Mapping

from deap import base as deap_base
from deap import cma as deap_cma
from deap import tools as deap_tools
from hand_codesign.core.search.pycma import cma
from hand_codesign.core.task.variant import Variant
import numpy as np

SIGMA0 = 0.1
"""Initial step size in the normalized genome space (section III.D)."""

STATE_FORMAT = 1


class OptimizerError(ValueError):
    """A wrong use of an optimizer or a state that cannot be restored."""


class TellError(OptimizerError):
    """
    The evaluations told do not match the candidates asked.

    The offending ids are in `missing`, `unknown`, `duplicated` and `invalid` (lists of ints).
    """

    def __init__(self, message, missing=(), unknown=(), duplicated=(), invalid=()):
        super().__init__(message)
        self.missing = sorted(missing)
        self.unknown = sorted(unknown)
        self.duplicated = sorted(duplicated)
        self.invalid = sorted(invalid)


class ReplayError(OptimizerError):
    """Recorded evaluations do not belong to the run being rebuilt."""


@dataclasses.dataclass(frozen=True)
class Candidate:
    """
    One design to evaluate: its id (unique within a run), generation and normalized genome.

    `variant` says which version of the run's task it is evaluated on (core.task.variant: its
    structure, worlds, horizon, stage, held-out worlds, resampled draw); the search sets it,
    the run's task itself until then. `share` (first, end) is a racing round's share of those
    worlds (core.search.racing; Candidate.worlds_from / worlds_to); () all of them.
    """

    candidate_id: int
    generation: int
    x: np.ndarray
    variant: Variant = Variant()
    share: tuple = ()


@dataclasses.dataclass(frozen=True)
class OptimizerResult:
    """
    The best design found so far, and for MO-CMA-ES the Pareto front it was chosen from.

    For CMA-ES the best design is the lowest weighted sum ever told (the earliest on ties); for
    MO-CMA-ES it is the point of the current Pareto front closest to zero after normalizing each
    objective between its minimum and maximum on the front (section III.C).
    """

    candidate_id: int
    generation: int
    x: np.ndarray
    objectives: np.ndarray
    fitness: float  # weighted sum of the objectives
    evaluations: int  # evaluations told so far
    iterations: int  # generations told so far
    pareto_ids: tuple = ()
    pareto_x: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 0)))
    pareto_objectives: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 0)))


def derived_seed(seed, *path):
    """Return the seed of one part of a run from the run's seed and the part's indices."""
    words = [int(seed)] + [int(part) for part in path]
    return int(np.random.SeedSequence(words).generate_state(1)[0])


def library_seed(seed):
    """Return the 32-bit nonzero seed of the private global generators derived from `seed`."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise OptimizerError(f'seed must be a non-negative integer, got {seed!r}')
    # Nonzero: pycma and numpy read a seed of 0 as "seed from the clock" in some places.
    return int(np.random.SeedSequence(int(seed)).generate_state(1)[0]) or 1


class AskTellOptimizer:
    """Common ask/tell bookkeeping: ids, generations, checks, best design and private RNG."""

    algorithm = ''

    def __init__(self, dim, weights, population, iterations, seed, first_id=0, x0=None,
                 sigma0=SIGMA0):
        self.dim = _positive_int('dim', dim)
        self.population = _positive_int('population', population, minimum=2)
        self.iterations = _positive_int('iterations', iterations)
        self.weights = np.array(weights, dtype=float).reshape(-1)
        if self.weights.size == 0 or not np.all(np.isfinite(self.weights)):
            raise OptimizerError(f'weights must be a non-empty finite vector, got {weights!r}')
        self.num_objectives = self.weights.size
        self.seed = int(seed)
        self.sigma0 = float(sigma0)
        if not self.sigma0 > 0:
            raise OptimizerError(f'sigma0 must be positive, got {sigma0!r}')
        self.x0 = np.full(self.dim, 0.5) if x0 is None else np.array(x0, dtype=float)
        if self.x0.shape != (self.dim,) or not np.all(np.isfinite(self.x0)):
            raise OptimizerError(
                f'start point must be {self.dim} finite normalized values, got shape '
                f'{self.x0.shape}')
        self.first_id = _positive_int('first_id', first_id, minimum=0)
        lib_seed = library_seed(seed)
        self._np_state = np.random.RandomState(lib_seed).get_state()
        self._py_state = random.Random(lib_seed).getstate()
        self._next_id = self.first_id
        self._generation = 0
        self._evaluations = 0
        self._pending = None  # the candidates of the generation asked and not yet told
        self._told_ids = set()
        self._incomplete = set()  # ids of the generation being told that a race stopped early
        self._best = None  # (fitness, candidate_id, generation, x, objectives)

    # -- the pycma-like interface ---------------------------------------------------------

    def ask(self):
        """Return the candidates of the next generation (the same ones again until told)."""
        if self._pending is None:
            with self._private_rng():
                points = self._sample()
            candidates = []
            for point in points:
                x = np.array(point, dtype=float)
                x.flags.writeable = False
                candidates.append(Candidate(self._next_id, self._generation, x))
                self._next_id += 1
            self._pending = (candidates, points)
        return list(self._pending[0])

    def tell(self, results):
        """
        Tell the evaluations of the asked generation: a mapping id -> objective vector.

        A sequence of (id, objectives) pairs is accepted as well, and an objective vector may be
        anything with an `objectives` attribute (an Evaluation). Raise TellError naming the ids
        when any asked id is missing, unknown, duplicated, or its objectives are not
        `num_objectives` finite numbers; the optimizer is then unchanged.
        """
        if self._pending is None:
            raise TellError('tell() without a generation asked: call ask() first')
        candidates, points = self._pending
        pairs = list(results.items()) if isinstance(results, Mapping) else list(results)
        by_id = self._check_results(candidates, pairs)
        objectives = np.array([by_id[c.candidate_id] for c in candidates])
        # a raced candidate stopped early (core.search.racing) is told the mean of a share of
        # its worlds: never the best design, and ranked by the optimizer as it says
        self._incomplete = {int(key) for key, values in pairs
                            if getattr(values, 'complete', True) is False}
        with self._private_rng():
            self._update(points, objectives)
        for candidate, values in zip(candidates, objectives):
            if candidate.candidate_id not in self._incomplete:
                self._record_best(candidate, values)
            self._told_ids.add(candidate.candidate_id)
        self._evaluations += len(candidates)
        self._generation += 1
        self._pending = None

    def stop(self):
        """Return why the optimization stopped, as a dict; empty while it runs."""
        if self._generation >= self.iterations:
            return {'maxiter': self.iterations}
        return {}

    @property
    def result(self):
        """Return the best design as an OptimizerResult, or None before the first tell."""
        if self._best is None:
            return None
        fitness, candidate_id, generation, x, objectives = self._best
        return OptimizerResult(candidate_id, generation, x, objectives, fitness,
                               self._evaluations, self._generation)

    @property
    def generation(self):
        """Return the number of generations told (the generation that ask() returns next)."""
        return self._generation

    @property
    def evaluations(self):
        """Return the number of evaluations told."""
        return self._evaluations

    @property
    def next_id(self):
        """Return the id that the next new candidate will get (continue a hierarchy from it)."""
        return self._next_id

    @property
    def pending(self):
        """Return the candidates asked and not yet told (an empty list when none)."""
        return [] if self._pending is None else list(self._pending[0])

    def fitness_of(self, objectives):
        """Return the weighted sum of an objective vector (what CMA-ES minimizes)."""
        return float(np.dot(self.weights, objectives))

    # -- saving and restoring ---------------------------------------------------------------

    def get_state(self):
        """Return the whole state as bytes; `from_state` continues from it bit-identically."""
        return pickle.dumps({'format': STATE_FORMAT, 'optimizer': self},
                            protocol=pickle.HIGHEST_PROTOCOL)

    @classmethod
    def from_state(cls, state):
        """Return the optimizer saved by `get_state`."""
        try:
            saved = pickle.loads(state)
        except (pickle.UnpicklingError, EOFError, AttributeError, ImportError, TypeError) as exc:
            raise OptimizerError(f'optimizer state cannot be read: {exc}') from exc
        found = saved.get('format') if isinstance(saved, dict) else None
        if found != STATE_FORMAT:
            raise OptimizerError(
                f'optimizer state has format {found!r}, expected {STATE_FORMAT}')
        optimizer = saved['optimizer']
        if not isinstance(optimizer, cls):
            raise OptimizerError(
                f'optimizer state holds a {type(optimizer).__name__}, expected a {cls.__name__}')
        return optimizer

    # -- for subclasses -----------------------------------------------------------------------

    def _sample(self):
        """Return the points of the next generation (runs with the private RNG)."""
        raise NotImplementedError

    def _update(self, points, objectives):
        """Update the search distribution (runs with the private RNG)."""
        raise NotImplementedError

    @contextlib.contextmanager
    def _private_rng(self):
        outer_np = np.random.get_state()
        outer_py = random.getstate()
        np.random.set_state(self._np_state)
        random.setstate(self._py_state)
        try:
            yield
        finally:
            self._np_state = np.random.get_state()
            self._py_state = random.getstate()
            np.random.set_state(outer_np)
            random.setstate(outer_py)

    def _record_best(self, candidate, objectives):
        fitness = self.fitness_of(objectives)
        if self._best is None or fitness < self._best[0]:
            self._best = (fitness, candidate.candidate_id, candidate.generation,
                          candidate.x, objectives.copy())

    def _check_results(self, candidates, results):
        pairs = list(results.items()) if isinstance(results, Mapping) else list(results)
        asked = {c.candidate_id for c in candidates}
        by_id, duplicated, unknown, invalid = {}, set(), set(), set()
        for pair in pairs:
            try:
                key, values = pair
                candidate_id = int(key)
            except (TypeError, ValueError) as exc:
                raise TellError(f'tell() takes id -> objectives, got an entry {pair!r}') from exc
            if candidate_id not in asked:
                unknown.add(candidate_id)
                continue
            if candidate_id in by_id:
                duplicated.add(candidate_id)
                continue
            vector = _objective_vector(values)
            if vector is None or vector.shape != (self.num_objectives,):
                invalid.add(candidate_id)
                continue
            by_id[candidate_id] = vector
        missing = asked - set(by_id) - invalid
        if missing or unknown or duplicated or invalid:
            generation = candidates[0].generation
            problems = []
            if missing:
                problems.append(f'missing ids {sorted(missing)}')
            if unknown:
                earlier = sorted(unknown & self._told_ids)
                problems.append(f'unknown ids {sorted(unknown)}' + (
                    f' ({earlier} were told in an earlier generation)' if earlier else ''))
            if duplicated:
                problems.append(f'duplicated ids {sorted(duplicated)}')
            if invalid:
                problems.append(f'ids {sorted(invalid)} without {self.num_objectives} finite '
                                'objective values')
            raise TellError(
                f'tell() refused for generation {generation} (ids {candidates[0].candidate_id}'
                f'..{candidates[-1].candidate_id}): ' + '; '.join(problems),
                missing=missing, unknown=unknown, duplicated=duplicated, invalid=invalid)
        return by_id


class CmaEs(AskTellOptimizer):
    """
    CMA-ES (pycma) minimizing the weighted sum of the objectives, without log files.

    pycma's own termination criteria (tolfun, tolx, ...) stay active besides the iteration
    budget; `stop()` returns pycma's dict of the criteria met.

    raced=True (a task with `worlds.racing`, core.search.racing): pycma runs without its
    negative (active) weights, so only the `selected` best ranks move the distribution, and a
    candidate told as stopped early (complete=False) is ranked after every complete one, in
    the order of its fitness so far. The race stops only candidates that at least `selected`
    complete ones beat, so the ranks that carry weight are all known.
    """

    algorithm = 'cma'

    def __init__(self, dim, weights, population, iterations, seed, first_id=0, x0=None,
                 sigma0=SIGMA0, raced=False):
        super().__init__(dim, weights, population, iterations, seed, first_id, x0, sigma0)
        self.raced = bool(raced)
        options = {
            # The optimizer seeds its private global generator itself (see _private_rng).
            'seed': np.nan,
            'randn': _global_randn,
            'popsize': self.population,
            'maxiter': self.iterations,
            'verbose': -9,
            'verb_disp': 0,
            'verb_log': 0,
            'verb_plot': 0,
        }
        if self.raced:
            options['CMA_active'] = False
        with self._private_rng():
            self._es = cma.CMAEvolutionStrategy(self.x0, self.sigma0, options)
        self._before_ask = None
        self._stop_dict = {}

    def stop(self):
        """Return pycma's termination criteria met (incl. 'maxiter'); empty while it runs."""
        return dict(self._stop_dict)

    def _sample(self):
        # pycma keys its record of sent solutions by hash(bytes), which differs between
        # processes; a restored state re-asks from this snapshot instead (see __setstate__).
        self._before_ask = pickle.dumps((self._es, self._np_state_in_use()),
                                        protocol=pickle.HIGHEST_PROTOCOL)
        return self._es.ask()

    @property
    def selected(self):
        """Return mu: how many of a generation's best ranks carry a positive weight."""
        return int(self._es.sp.weights.mu)

    def _ranking(self, objectives):
        """Return the fitness pycma ranks by: stopped candidates after every complete one."""
        fitness = [self.fitness_of(values) for values in objectives]
        stopped = [candidate.candidate_id in self._incomplete for candidate in self._pending[0]]
        ceiling = max([value for value, out in zip(fitness, stopped) if not out], default=0.0)
        # a stopped candidate's fitness so far is positive (core.search.racing): the sum
        # keeps it above the ceiling and the stopped ones in their order
        return [ceiling + value if out else value for value, out in zip(fitness, stopped)]

    def _update(self, points, objectives):
        self._es.tell(points, self._ranking(objectives))
        self._before_ask = None
        # pycma's stop() advances counters (e.g. of flat fitness) at every call: check once per
        # generation so that how often callers ask cannot change the run.
        self._stop_dict = dict(self._es.stop())

    @staticmethod
    def _np_state_in_use():
        return np.random.get_state()

    def __getstate__(self):
        state = self.__dict__.copy()
        if self._pending is not None:
            state['_es'] = None
            state['_pending'] = (self._pending[0], None)
        else:
            state['_before_ask'] = None
        return state

    def __setstate__(self, state):
        self.__dict__.update(state)
        if self._es is None:
            candidates = self._pending[0]
            self._es, before_np_state = pickle.loads(self._before_ask)
            after_np_state = self._np_state
            self._np_state = before_np_state
            with self._private_rng():
                points = self._sample()
            if (len(points) != len(candidates) or
                    not all(np.array_equal(p, c.x) for p, c in zip(points, candidates))):
                raise OptimizerError('restored CMA-ES state does not reproduce its pending '
                                     'candidates (was it saved by another pycma version?)')
            if not _same_np_state(self._np_state, after_np_state):
                raise OptimizerError('restored CMA-ES state does not reproduce its generator')
            self._pending = (candidates, points)


class _MinimizingFitness(deap_base.Fitness):
    """A DEAP fitness that minimizes every one of its values."""

    weights = ()

    def __init__(self, values=()):
        self.weights = (-1.0,) * len(values)
        super().__init__(values)

    def __deepcopy__(self, memo):
        return _MinimizingFitness(self.values)


class _Individual(list):
    """A point of DEAP's MO-CMA-ES: a list of floats with a `fitness` and a `candidate_id`."""


def least_hypervolume_contributor(front, ref=None):
    """
    Return the index of the point of `front` whose removal loses the least hypervolume.

    The indicator of DEAP's MO-CMA-ES selection (deap.tools.hypervolume), exact and in
    O(n log n) for two objectives instead of n hypervolume computations; ties go to the first.
    `front` holds mutually non-dominated individuals with minimizing fitnesses.
    """
    values = np.array([ind.fitness.values for ind in front], dtype=float)
    if values.shape[1] != 2:
        return deap_tools.hypervolume(front, ref=ref)
    reference = values.max(axis=0) + 1.0 if ref is None else np.asarray(ref, dtype=float)
    # Along the front sorted by the first objective the second decreases; each point owns the
    # rectangle up to its right neighbour's first and its left neighbour's second objective.
    order = np.lexsort((-values[:, 1], values[:, 0]))
    ordered = values[order]
    right = np.append(ordered[1:, 0], reference[0])
    upper = np.insert(ordered[:-1, 1], 0, reference[1])
    contribution = np.empty(len(values))
    contribution[order] = (right - ordered[:, 0]) * (upper - ordered[:, 1])
    return int(np.argmin(contribution))


class _MultiObjectiveStrategy(deap_cma.StrategyMultiObjective):
    """DEAP's MO-CMA-ES, also for a single objective (DEAP's non-dominated sort needs two)."""

    def _select(self, candidates):
        if len(candidates) <= self.mu or len(candidates[0].fitness.values) > 1:
            return super()._select(candidates)
        # One objective: the fronts are the distinct values, so keep the mu lowest (stable).
        ranked = sorted(candidates, key=lambda ind: ind.fitness.values[0])
        return ranked[:self.mu], ranked[self.mu:]


class MoCmaEs(AskTellOptimizer):
    """
    MO-CMA-ES (Igel et al. with Voss et al.'s step size rule) by DEAP's StrategyMultiObjective.

    Generation 0 samples `population` points around the start point (step size sigma0), which
    become the mu parents; every later generation is one (mu + lambda) step with
    mu = lambda = population (each parent produces one offspring). Generation 0 counts towards
    the iteration budget.
    """

    algorithm = 'mocma'

    def __init__(self, dim, weights, population, iterations, seed, first_id=0, x0=None,
                 sigma0=SIGMA0, front_choice='normalized'):
        super().__init__(dim, weights, population, iterations, seed, first_id, x0, sigma0)
        self._strategy = None
        self.front_choice = front_choice

    @property
    def result(self):
        """Return the design of the Pareto front that front_choice picks (front_index)."""
        if self._strategy is None:
            return None
        front = self._pareto_front()
        ids = tuple(ind.candidate_id for ind in front)
        xs = np.array([ind.x for ind in front])
        objectives = np.array([ind.fitness.values for ind in front], dtype=float)
        # getattr: a state saved before front_choice existed picks as it did then
        best = front_index(objectives, self.weights, getattr(self, 'front_choice', 'normalized'))
        return OptimizerResult(
            ids[best], front[best].generation, front[best].x, objectives[best].copy(),
            self.fitness_of(objectives[best]), self._evaluations, self._generation,
            pareto_ids=ids, pareto_x=xs, pareto_objectives=objectives)

    def _pareto_front(self):
        parents = sorted(self._strategy.parents, key=lambda ind: ind.candidate_id)
        values = np.array([ind.fitness.values for ind in parents])
        return [parents[i] for i in np.flatnonzero(non_dominated(values))]

    def ask(self):
        """Return the candidates of the next generation (the same ones again until told)."""
        candidates = super().ask()
        for candidate, individual in zip(candidates, self._pending[1]):
            individual.candidate_id = candidate.candidate_id
            individual.generation = candidate.generation
            individual.x = candidate.x
        return candidates

    def _sample(self):
        if self._strategy is None:
            points = self.x0 + self.sigma0 * np.random.standard_normal((self.population, self.dim))
            return [_Individual(point) for point in points]
        return self._strategy.generate(_Individual)

    def _update(self, points, objectives):
        for individual, values in zip(points, objectives):
            individual.fitness = _MinimizingFitness(tuple(float(v) for v in values))
        if self._strategy is None:
            self._strategy = _MultiObjectiveStrategy(
                list(points), sigma=self.sigma0, mu=self.population, lambda_=self.population,
                indicator=least_hypervolume_contributor)
        else:
            self._strategy.update(list(points))


def non_dominated(objectives):
    """Return a boolean mask of the rows (minimized objectives) that no other row dominates."""
    objectives = np.asarray(objectives, dtype=float)
    no_worse = np.all(objectives[:, None, :] <= objectives[None, :, :], axis=2)
    better = np.any(objectives[:, None, :] < objectives[None, :, :], axis=2)
    dominated = np.any(no_worse & better, axis=0)  # [j, i]: row j dominates row i
    return ~dominated


def closest_to_zero(objectives):
    """
    Return the row index closest to zero after min-max normalizing each column (III.C).

    A column with equal values normalizes to 0; ties go to the first row.
    """
    objectives = np.asarray(objectives, dtype=float)
    low = objectives.min(axis=0)
    span = objectives.max(axis=0) - low
    normalized = np.divide(objectives - low, span, out=np.zeros_like(objectives),
                           where=span > 0)
    return int(np.argmin(np.linalg.norm(normalized, axis=1)))


def front_index(objectives, weights, choice='normalized'):
    """
    Return the row of a Pareto front (rows: designs, columns: minimized objectives) to report.

    'normalized' is the paper's rule (closest_to_zero, III.C); 'weighted' the row with the
    least weighted sum (weights: one per column, the task's), ties to the first row. The
    normalized rule depends on the front's extremes: a front that reaches far along one
    objective stretches that column, and its chosen point moves towards the other.
    """
    if choice == 'weighted':
        return int(np.argmin(np.asarray(objectives, dtype=float) @ np.asarray(weights)))
    return closest_to_zero(objectives)


def replay(optimizer, recorded, recorded_x=None):
    """
    Rebuild a run by telling a fresh optimizer (same task and seed) its recorded evaluations.

    `recorded` maps candidate id -> objectives (as from a bag's Evaluation messages). Whole
    generations are told in order until one is not fully recorded; its candidates stay pending,
    so that the caller evaluates only those missing from `recorded`. With `recorded_x`
    (id -> normalized genome, from the Candidate messages) every asked genome is checked against
    the recording. Works for anything with ask/tell/stop (also a HierarchySearch).

    Return the number of generations told. Raise ReplayError when the recording disagrees with
    the optimizer.
    """
    told = 0
    while not optimizer.stop():
        candidates = optimizer.ask()
        if recorded_x is not None:
            for candidate in candidates:
                if (candidate.candidate_id in recorded_x and not np.array_equal(
                        np.asarray(recorded_x[candidate.candidate_id], dtype=float),
                        candidate.x)):
                    raise ReplayError(
                        f'candidate {candidate.candidate_id} of generation '
                        f'{candidate.generation}: recorded genome differs from the one asked '
                        '(different task, seed or library version?)')
        if not all(c.candidate_id in recorded for c in candidates):
            break
        optimizer.tell({c.candidate_id: recorded[c.candidate_id] for c in candidates})
        told += 1
    return told


def _global_randn(*shape):
    """
    Draw from numpy's global generator, found at call time (pycma's sampler).

    pycma's default, the bound method np.random.randn, pickles a copy of the global generator
    into the state and draws from that copy after a restore.
    """
    return np.random.randn(*shape)


def _objective_vector(values):
    values = getattr(values, 'objectives', values)
    try:
        vector = np.array(values, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        return None
    if not np.all(np.isfinite(vector)):
        return None
    return vector


def _positive_int(name, value, minimum=1):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise OptimizerError(f'{name} must be an integer >= {minimum}, got {value!r}')
    return int(value)


def _same_np_state(first, second):
    return (first[0] == second[0] and np.array_equal(first[1], second[1]) and
            first[2:] == second[2:])


__all__ = [
    'AskTellOptimizer', 'Candidate', 'CmaEs', 'MoCmaEs', 'OptimizerError', 'OptimizerResult',
    'ReplayError', 'SIGMA0', 'TellError', 'closest_to_zero', 'derived_seed', 'front_index',
    'least_hypervolume_contributor', 'library_seed', 'non_dominated', 'replay',
]
