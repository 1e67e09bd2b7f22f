"""
CMA-ES with restarts and growing populations, IPOP and BIPOP, under the ask/tell contract.

IPOP-CMA-ES (Auger and Hansen 2005, "A restart CMA evolution strategy with increasing
population size", CEC 2005) runs CMA-ES until it stops by its own criteria, then starts it
again from a new point with twice the population: a larger population smooths a rugged
landscape and finds the global structure of multimodal functions that a small one misses.
BIPOP-CMA-ES (Hansen 2009, "Benchmarking a BI-population CMA-ES on the BBOB-2009 function
testbed", GECCO workshop) interleaves those large-population runs with runs of a random
smaller population and step size, for functions whose good basins are small.

pycma offers both only inside `cma.fmin`, which owns the loop; here they are AskTellOptimizers
like `core.search.optimizers.CmaEs`, so that the optimizer node, replay, resume and the hierarchy
drive them alike. Each CMA-ES instance is a CmaEs of its own (seeded with
`derived_seed(seed, restart index)`), which already pickles and continues bit-identically;
this module decides when an instance ends and how the next one starts. The choices:

- The budget keeps its meaning for every algorithm: a run spends `iterations x population`
  evaluations, `population` being the first instance's; generations of a larger population
  count for more, and the last generation is cut to the evaluations left (its candidates are
  the first ones its instance samples; the instance is not told them, nothing follows).
  `stop()` returns {'maxfevals': budget, 'restarts': count} once it is spent.
- An instance ends (and the next starts, if budget is left) on any of pycma's own termination
  criteria (tolfun, tolfunhist, tolflatfitness, tolx, tolupsigma, tolstagnation,
  tolconditioncov, noeffectaxis, noeffectcoord, ...), its defaults being the criteria of
  Auger and Hansen 2005. The budget criteria (maxfevals, timeout) are never set on an instance;
  pycma's maxiter is, only as the budget of a BIPOP small-population run.
- It also ends when its best weighted sum has not improved for a number of generations:
  `stagnation` if given (`optimizer.restart_stagnation` of a task), else twice
  10 + ceil(30 n / lambda), the history length of pycma's tolfunhist (the window in which
  Auger and Hansen call a history of best values flat). pycma's own tolstagnation waits
  100 + 100 n^1.5 / lambda generations, more than a whole run of most tasks here (n = 20 to 60
  genes, 100 generations), so that it would never restart a co-design run stuck on a plateau
  that is not quite flat (early termination, collisions). Once the window is too short: the
  wide first generations of an instance often hold its best sample for long while the mean
  descends into a basin, and an instance ended then is wasted. Measured with
  bench/compare_restarts.py's function (Rastrigin 10-D, 20000 evaluations, seeds 1 to 5):
  median best 18.9 with the window once, 2.98 with it twice, three or five times, or without
  this rule at all.
- The first instance starts where CmaEs would (the task's seed design or the centre of the
  bounds) with the task's step size; every later one at a point drawn uniformly in [0, 1]^n
  (the normalized genome space) from the optimizer's own generator. IPOP keeps the step size
  of the first instance and doubles the population at every restart.
- BIPOP as Hansen 2009, with the first run counted for the small regime as pycma counts it:
  the next run is a small-population one while the small regime has spent fewer evaluations
  than the large one, else a large one (population lambda0 2^k for the k-th large run, the
  task's step size). A small run draws U1, U2 uniform in [0, 1]: population
  floor(lambda0 (lambda_L / lambda0)^(U1^2)) (lambda_L the latest large population), step size
  sigma0 10^(-2 U2), and at most half the evaluations of the latest large run.
- The best design (`result`) is the lowest weighted sum ever told, across restarts; generation
  numbers and candidate ids keep increasing across restarts. `restarts` lists every instance
  (where it started, its population, step size, regime and why the one before it ended), and
  `restart_of(generation)` the instance a generation belongs to.
"""

import dataclasses
import math

from hand_codesign.core.search.optimizers import AskTellOptimizer
from hand_codesign.core.search.optimizers import CmaEs
from hand_codesign.core.search.optimizers import derived_seed
from hand_codesign.core.search.optimizers import OptimizerError
from hand_codesign.core.search.optimizers import SIGMA0
import numpy as np

POPULATION_FACTOR = 2
"""IPOP's factor of the population at each (large) restart (Auger and Hansen 2005)."""

STAGNATION_FACTOR = 2
"""The default stagnation window in tolfunhist windows of pycma (see the module doc)."""

FIRST, LARGE, SMALL = 'first', 'large', 'small'


@dataclasses.dataclass(frozen=True)
class Restart:
    """One CMA-ES instance of a restart run: where and how it started, and why."""

    index: int            # 0 for the first instance
    generation: int       # the run's generation of its first candidates
    evaluations: int      # evaluations told in the run before it started
    population: int
    sigma: float
    regime: str           # 'first', 'large' or 'small' (BIPOP's small-population regime)
    reason: str           # why the instance before it ended ('' for the first)
    max_generations: int  # its own generation budget (a BIPOP small run); 0: none
    start: tuple          # its start point (normalized genome)


class RestartCmaEs(AskTellOptimizer):
    """The restart loop common to IPOP and BIPOP: instances, budget, stagnation (module doc)."""

    def __init__(self, dim, weights, population, iterations, seed, first_id=0, x0=None,
                 sigma0=SIGMA0, stagnation=None):
        super().__init__(dim, weights, population, iterations, seed, first_id, x0, sigma0)
        if stagnation is not None and (isinstance(stagnation, bool) or not isinstance(
                stagnation, (int, np.integer)) or stagnation < 1):
            raise OptimizerError(f'stagnation must be an integer >= 1 or None, got '
                                 f'{stagnation!r}')
        self.stagnation = None if stagnation is None else int(stagnation)
        self.budget = self.iterations * self.population
        self.restarts = []
        self._instance = None
        self._begin(self.x0, self.population, self.sigma0, FIRST, '', 0, 0)

    def stop(self):
        """Return {'maxfevals': budget, 'restarts': count} once the budget is spent, else {}."""
        if self._evaluations >= self.budget:
            return {'maxfevals': self.budget, 'restarts': len(self.restarts) - 1}
        return {}

    def restart_of(self, generation):
        """Return the Restart (instance) that generation `generation` of the run belongs to."""
        found = self.restarts[0]
        for restart in self.restarts:
            if restart.generation <= generation:
                found = restart
        return found

    def stagnation_window(self, population):
        """Return the generations without improvement after which an instance ends."""
        if self.stagnation is not None:
            return self.stagnation
        return STAGNATION_FACTOR * (10 + math.ceil(30 * self.dim / population))

    # -- the instances -------------------------------------------------------------------

    def _begin(self, x0, population, sigma, regime, reason, max_generations, spent):
        """Start the next CMA-ES instance at x0 (a CmaEs with a seed of its own); record it."""
        index = len(self.restarts)
        budget = max_generations or self.iterations  # a run has at most `iterations` of them
        self._instance = CmaEs(self.dim, self.weights, population, budget,
                               derived_seed(self.seed, index), x0=x0, sigma0=sigma)
        self.restarts.append(Restart(index, self._generation + (1 if index else 0), spent,
                                     int(population), float(sigma), regime, reason,
                                     int(max_generations), tuple(float(v) for v in x0)))

    def _sample(self):
        left = self.budget - self._evaluations
        if left <= 0:
            raise OptimizerError(f'the budget of {self.budget} evaluations is spent: ask() '
                                 'after stop()')
        return [candidate.x for candidate in self._instance.ask()][:left]

    def _update(self, points, objectives):
        asked = self._instance.ask()
        if len(points) < len(asked):
            return  # the budget's last generation, cut short: no instance follows
        self._instance.tell({candidate.candidate_id: values
                             for candidate, values in zip(asked, objectives)})
        spent = self._evaluations + len(points)
        if spent >= self.budget:
            return
        reason = self._end_reason()
        if reason:
            start = np.random.uniform(0.0, 1.0, self.dim)
            population, sigma, regime, max_generations = self._next_instance(spent)
            self._begin(start, population, sigma, regime, reason, max_generations, spent)

    def _end_reason(self):
        """Return why the current instance ends ('' while it goes on)."""
        stopped = self._instance.stop()
        if stopped:
            return ', '.join(sorted(stopped))
        instance = self._instance
        idle = instance.generation - 1 - instance.result.generation
        window = self.stagnation_window(instance.population)
        if idle >= window:
            return f'stagnation: {idle} generation{"s" if idle > 1 else ""} without improvement'
        return ''

    def _next_instance(self, spent):
        """Return (population, sigma, regime, max_generations) of the next instance."""
        raise NotImplementedError


class IpopCmaEs(RestartCmaEs):
    """IPOP-CMA-ES (Auger and Hansen 2005): every restart doubles the population."""

    algorithm = 'ipop-cma'

    def _next_instance(self, spent):
        return (self.restarts[-1].population * POPULATION_FACTOR, self.sigma0, LARGE, 0)


class BipopCmaEs(RestartCmaEs):
    """BIPOP-CMA-ES (Hansen 2009): large-population runs interleaved with small ones."""

    algorithm = 'bipop-cma'

    def regime_evaluations(self, spent=None):
        """Return {'small': n, 'large': n}: evaluations spent so far in each regime."""
        spent = self._evaluations if spent is None else spent
        totals = {SMALL: 0, LARGE: 0}
        ends = [restart.evaluations for restart in self.restarts[1:]] + [spent]
        for restart, end in zip(self.restarts, ends):
            # the first run counts for the small regime, as pycma's BIPOP counts it
            totals[LARGE if restart.regime == LARGE else SMALL] += end - restart.evaluations
        return totals

    def _next_instance(self, spent):
        totals = self.regime_evaluations(spent)
        large = [restart for restart in self.restarts if restart.regime == LARGE]
        if not large or totals[SMALL] >= totals[LARGE]:
            return (self.population * POPULATION_FACTOR ** (len(large) + 1), self.sigma0,
                    LARGE, 0)
        ratio, exponent = np.random.uniform(0.0, 1.0, 2)
        latest = large[-1]
        population = int(math.floor(
            self.population * (latest.population / self.population) ** (ratio ** 2)))
        latest_spent = self._spent_by(latest, spent)
        max_generations = max(1, int(0.5 * latest_spent // population))
        return population, self.sigma0 * 10.0 ** (-2.0 * exponent), SMALL, max_generations

    def _spent_by(self, restart, spent):
        later = [other.evaluations for other in self.restarts if other.index > restart.index]
        return (later[0] if later else spent) - restart.evaluations


ALGORITHMS = {IpopCmaEs.algorithm: IpopCmaEs, BipopCmaEs.algorithm: BipopCmaEs}

__all__ = ['ALGORITHMS', 'BipopCmaEs', 'IpopCmaEs', 'POPULATION_FACTOR', 'Restart',
           'RestartCmaEs', 'STAGNATION_FACTOR']
