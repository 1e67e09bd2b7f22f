"""
Quality-diversity search under ask/tell: CMA-MAE and CMA-ME (pyribs) over design descriptors.

CMA-ES returns one design; quality-diversity search returns an archive of them, the best it
found in each cell of a grid over two descriptors of the design (core.task.descriptors: e.g. total
finger length and mean joint-limit span), so that a person can pick among diverse good hands
(the paper's future work). Both algorithms run CMA-ES emitters that rank their samples by how
much they improve the archive rather than by their quality alone:

- CMA-ME (Fontaine, Togelius, Nikolaidis and Hoover 2020, "Covariance Matrix Adaptation for
  the Rapid Illumination of Behavior Space", GECCO): improvement emitters (pyribs's ranker
  '2imp', 'filter' selection, restart when no sample enters the archive); an elite is replaced
  by any better design.
- CMA-MAE (Fontaine and Nikolaidis 2023, "Covariance Matrix Adaptation MAP-Annealing",
  GECCO): each cell has a threshold that an entering design raises by a learning rate alpha
  (default 0.01) towards its quality, ranker 'imp', 'mu' selection, CMA-ES's own restart rules.
  alpha = 0 is CMA-ES on the quality, alpha = 1 is CMA-ME; in between the emitters leave
  cells they have improved enough. The designs the annealed archive drops are kept in a result
  archive (learning rate 1): that one is the run's archive.

The choices that keep the contracts of `core.search.optimizers`:

- Quality: pyribs maximizes, so the quality is minus the weighted sum of the objectives that
  CMA-ES minimizes. The run's result (`result`) is the lowest weighted sum ever told, which is
  always the elite of its cell in the result archive: the design the archive recommends.
- Budget: `population` candidates per generation, split over the emitters (the first ones get
  one more when it does not divide; `emitters` defaults to one per CANDIDATES_PER_EMITTER
  candidates), `iterations` generations. Generation 0 samples `population` points around the
  start point (the centre of the bounds or the seeded design, step size sigma0) as MO-CMA-ES's
  does; it fills the archive and sets CMA-MAE's minimum threshold to the median quality of
  generation 0 (the quality scale differs between tasks: no constant would fit all, and half
  of generation 0 enters, so the emitters' restarts always find an elite to start from). From
  generation 1 on, every emitter starts at the start point with step size sigma0.
- Seeds: archive, result archive and each emitter get `derived_seed(seed, part)`; generation 0
  draws from the optimizer's private generator. pyribs draws from its own numpy Generators,
  which pickle with the rest of the state: `get_state` / `from_state` continue bit-identically.
- The genome space stays the unbounded normalized one of CMA-ES (no bounds on the emitters).
- Outcome descriptors (core.outcomes: limit_rest, touch) come from the evaluations: `tell`
  takes, per id, an objective vector, or anything with `objectives`, `outcome_names` and
  `outcomes` (a core.outcomes.Answer, an Evaluation); a candidate whose answer lacks an
  outcome the archive spans is refused like one without objectives (TellError). Replaying a
  run needs them again: records and resume read them from the bag's Evaluation messages.
"""

from collections.abc import Mapping
import dataclasses
import importlib.util

from hand_codesign.core.outcomes import outcomes_of
from hand_codesign.core.search.optimizers import AskTellOptimizer
from hand_codesign.core.search.optimizers import derived_seed
from hand_codesign.core.search.optimizers import OptimizerError
from hand_codesign.core.search.optimizers import SIGMA0
from hand_codesign.core.search.optimizers import TellError
from hand_codesign.core.task.genome import fold
import numpy as np

DEFAULT_CELLS = (10, 10)
"""Cells of the archive along each descriptor."""

MAE_LEARNING_RATE = 0.01
"""CMA-MAE's alpha, as Fontaine and Nikolaidis 2023 ran it."""

CANDIDATES_PER_EMITTER = 10
"""The default number of emitters is population // this (at least one)."""

_ARCHIVE_SEED, _RESULT_SEED, _EMITTER_SEED = 1, 2, 3


@dataclasses.dataclass(frozen=True)
class Elite:
    """The best design of one cell of the archive."""

    candidate_id: int
    generation: int
    x: np.ndarray
    fitness: float  # weighted sum of the objectives
    descriptors: tuple
    cell: tuple  # its index along each descriptor


class GenomeDescriptors:
    """Two genes of the genome folded into [0, 1]: the descriptors of a bare optimizer."""

    names = ('gene_0', 'gene_1')
    units = ('', '')
    ranges = ((0.0, 1.0), (0.0, 1.0))

    def __call__(self, x):
        """Return the first two coordinates of x, folded into [0, 1]."""
        return fold(np.asarray(x, dtype=float)[:2])


class QualityDiversity(AskTellOptimizer):
    """The archive, emitters and scheduler common to CMA-ME and CMA-MAE (module doc)."""

    learning_rate = 1.0
    ranker = '2imp'
    selection_rule = 'filter'
    restart_rule = 'no_improvement'

    def __init__(self, dim, weights, population, iterations, seed, first_id=0, x0=None,
                 sigma0=SIGMA0, describe=None, cells=DEFAULT_CELLS, ranges=None,
                 emitters=None, learning_rate=None):
        super().__init__(dim, weights, population, iterations, seed, first_id, x0, sigma0)
        if importlib.util.find_spec('ribs') is None:   # optional: only this search needs it
            raise OptimizerError(f'{self.algorithm} needs pyribs, which is not installed: '
                                 'pip install ribs (pinned in requirements.txt, and in '
                                 'requirements-apt.txt for the apt path)')
        self.describe = GenomeDescriptors() if describe is None else describe
        self.cells = tuple(int(c) for c in cells)
        self.ranges = tuple(tuple(float(v) for v in r) for r in (
            self.describe.ranges if ranges is None else ranges))
        if len(self.cells) != 2 or min(self.cells) < 1:
            raise OptimizerError(f'cells must be two positive integers, got {cells!r}')
        if len(self.ranges) != 2 or not all(high > low for low, high in self.ranges):
            raise OptimizerError(f'ranges must be two (lower, upper) with lower < upper, got '
                                 f'{ranges!r}')
        count = max(1, self.population // CANDIDATES_PER_EMITTER) if emitters is None \
            else emitters
        if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or \
                not 1 <= count <= self.population // 2:
            raise OptimizerError(f'emitters must be an integer from 1 to population / 2 = '
                                 f'{self.population // 2} (each samples at least 2 '
                                 f'candidates), got {emitters!r}')
        if learning_rate is not None:
            self.learning_rate = float(learning_rate)
        if not 0.0 <= self.learning_rate <= 1.0:
            raise OptimizerError(f'learning_rate must be within [0, 1], got {learning_rate!r}')
        share, extra = divmod(self.population, int(count))
        self.batch_sizes = tuple(share + (1 if k < extra else 0) for k in range(int(count)))
        self.threshold = None  # the archive's minimum quality, set by generation 0
        self._scheduler = None
        self._outcomes = {}  # id -> {outcome: value} of the generation being told

    # -- the archive ------------------------------------------------------------------------

    @property
    def archive(self):
        """Return the pyribs archive of the run's elites (the result archive), or None."""
        return None if self._scheduler is None else self._scheduler.result_archive

    def elites(self):
        """Return the Elites of the archive, best (lowest weighted sum) first."""
        if self.archive is None:
            return []
        data = self.archive.data()
        cells = self.archive.int_to_grid_index(data['index'])
        order = np.lexsort((data['candidate_id'], -data['objective']))
        return [Elite(int(data['candidate_id'][i]), int(data['generation'][i]),
                      np.array(data['solution'][i], dtype=float), float(-data['objective'][i]),
                      tuple(float(v) for v in data['measures'][i]),
                      tuple(int(v) for v in cells[i])) for i in order]

    def fitness_grid(self):
        """Return the elites' weighted sums as a cells[0] x cells[1] array (nan: empty)."""
        grid = np.full(self.cells, np.nan)
        for elite in self.elites():
            grid[elite.cell] = elite.fitness
        return grid

    @property
    def emitter_restarts(self):
        """Return how often each emitter restarted its CMA-ES."""
        if self._scheduler is None:
            return [0] * len(self.batch_sizes)
        return [emitter.restarts for emitter in self._scheduler.emitters]

    # -- ask and tell -----------------------------------------------------------------------

    def tell(self, results):
        """Tell the asked generation's evaluations (AskTellOptimizer.tell), with outcomes."""
        wanted = getattr(self.describe, 'outcome_names', ())
        if not wanted:
            return super().tell(results)
        pairs = list(results.items()) if isinstance(results, Mapping) else list(results)
        outcomes = {}
        for pair in pairs:
            try:
                key, value = pair
                outcomes[int(key)] = outcomes_of(value)
            except (TypeError, ValueError):
                continue  # the base tell names the malformed entry
        lacking = sorted(candidate.candidate_id for candidate in self.pending
                         if not set(wanted) <= set(outcomes.get(candidate.candidate_id, {})))
        if lacking:
            raise TellError(f'tell() refused: ids {lacking} without the outcome descriptors '
                            f'{list(wanted)} the archive spans', invalid=lacking)
        self._outcomes = outcomes
        try:
            super().tell(pairs)
        finally:
            self._outcomes = {}

    def _sample(self):
        if self._scheduler is None:
            return list(self.x0 + self.sigma0 * np.random.standard_normal(
                (self.population, self.dim)))
        return [np.array(row, dtype=float) for row in self._scheduler.ask()]

    def _update(self, points, objectives):
        candidates = self._pending[0]
        fields = {
            'objective': -np.array([self.fitness_of(values) for values in objectives]),
            'measures': np.array([self._describe(point, c.candidate_id)
                                  for point, c in zip(points, candidates)], dtype=float),
            'candidate_id': np.array([c.candidate_id for c in candidates], dtype=np.int64),
            'generation': np.array([c.generation for c in candidates], dtype=np.int64),
        }
        if self._scheduler is None:
            self._start(np.array(points, dtype=float), fields)
        else:
            self._scheduler.tell(**fields)

    def _describe(self, point, candidate_id):
        """Return a told candidate's descriptors: of its genome, and its outcomes if needed."""
        if not getattr(self.describe, 'outcome_names', ()):
            return self.describe(point)
        return self.describe(point, self._outcomes[candidate_id])

    def _start(self, points, fields):
        """Build archives, emitters and scheduler; add generation 0 (module doc)."""
        # imported here: pyribs loads numba, which only a quality-diversity run needs
        from ribs.archives import GridArchive
        from ribs.emitters import EvolutionStrategyEmitter
        from ribs.schedulers import Scheduler
        self.threshold = self._minimum_threshold(fields['objective'])

        def grid(learning_rate, threshold, part):
            return GridArchive(
                solution_dim=self.dim, dims=self.cells, ranges=self.ranges,
                learning_rate=learning_rate, threshold_min=threshold,
                seed=derived_seed(self.seed, part), dtype=np.float64,
                extra_fields={'candidate_id': ((), np.int64), 'generation': ((), np.int64)})

        archive = grid(self.learning_rate, self.threshold, _ARCHIVE_SEED)
        result = None if self.learning_rate == 1.0 else grid(1.0, -np.inf, _RESULT_SEED)
        emitters = [EvolutionStrategyEmitter(
            archive, x0=self.x0, sigma0=self.sigma0, ranker=self.ranker,
            selection_rule=self.selection_rule, restart_rule=self.restart_rule,
            batch_size=size, seed=derived_seed(self.seed, _EMITTER_SEED, index))
            for index, size in enumerate(self.batch_sizes)]
        self._scheduler = Scheduler(archive, emitters, result_archive=result)
        archive.add(solution=points, **fields)
        if result is not None:
            result.add(solution=points, **fields)

    def _minimum_threshold(self, qualities):
        """Return the archive's threshold_min: none for CMA-ME, generation 0's median else."""
        if self.learning_rate == 1.0:
            return -np.inf
        median = float(np.median(qualities))
        # a little below the median, so that the median design itself enters
        return median - 1e-9 * max(1.0, abs(median))


class CmaMe(QualityDiversity):
    """CMA-ME (Fontaine et al. 2020): improvement emitters on an archive of elites."""

    algorithm = 'cma-me'


class CmaMae(QualityDiversity):
    """CMA-MAE (Fontaine and Nikolaidis 2023): improvement over annealed cell thresholds."""

    algorithm = 'cma-mae'
    learning_rate = MAE_LEARNING_RATE
    ranker = 'imp'
    selection_rule = 'mu'
    restart_rule = 'basic'


ALGORITHMS = {CmaMae.algorithm: CmaMae, CmaMe.algorithm: CmaMe}

__all__ = ['ALGORITHMS', 'CANDIDATES_PER_EMITTER', 'CmaMae', 'CmaMe', 'DEFAULT_CELLS', 'Elite',
           'GenomeDescriptors', 'MAE_LEARNING_RATE', 'QualityDiversity']
