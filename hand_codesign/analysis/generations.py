"""A run's generations read back from its bag: best and median per generation, fronts, restarts."""

from hand_codesign.analysis import records
import numpy as np


class Generations:
    """Per-generation statistics: structure, generation, best and median per objective."""

    def __init__(self, structures, generations, best, median, best_fitness, evaluations,
                 wall_time, source, rows=None):
        self.structures = structures        # list of tuples
        self.generations = generations      # np.ndarray of int
        self.best = best                    # (rows, objectives)
        self.median = median
        self.best_fitness = best_fitness    # best so far (NaN when unknown)
        self.evaluations = evaluations      # told so far (NaN when unknown)
        self.wall_time = wall_time
        self.source = source                # 'summaries' or 'evaluations'
        self.rows = rows                    # the GenerationSummary rows, when from summaries
        self.horizons = np.zeros(len(generations))  # s, of a staged search (0: none)
        self.stages = np.zeros(len(generations), dtype=int)  # of a two-stage task (0: none)

    def __len__(self):
        return len(self.generations)


def _structure_tuples(column, count):
    if count == 0:
        return []
    return [tuple(int(joints) for joints in column[index]) for index in range(count)]


STAGE_WORLDS = {1: 'the nominal world only', 2: 'the randomized worlds'}


def generations_from_summaries(record, num_objectives):
    """Return the Generations of the GenerationSummary messages (the final repeat dropped)."""
    summaries = record.generation_summaries
    structures = _structure_tuples(summaries['structure'], len(summaries))
    generation = np.asarray(summaries['generation'], dtype=np.int64)
    final = np.asarray(summaries['final'], dtype=bool)
    # a hierarchy's check of a structure's best design is not a generation of the search
    keep = (~np.asarray(summaries['check'], dtype=bool) if 'check' in summaries
            else np.ones(len(summaries), dtype=bool))
    previous = None
    for index in np.flatnonzero(keep):
        # the final summary repeats the last generation's statistics with final = true
        if (final[index] and previous is not None and generation[index] == generation[previous]
                and structures[index] == structures[previous]):
            keep[index] = False
        previous = index
    rows = np.flatnonzero(keep)
    best = records._row_matrix(summaries['best'], rows, num_objectives)
    median = records._row_matrix(summaries['median'], rows, num_objectives)
    generations = Generations(
        [structures[row] for row in rows], generation[rows], best, median,
        np.asarray(summaries['best_fitness'], dtype=float)[rows],
        np.asarray(summaries['evaluations'], dtype=float)[rows],
        np.asarray(summaries['wall_time'], dtype=float)[rows], 'summaries', rows)
    if 'horizon' in summaries:  # older bags have no horizon
        generations.horizons = np.asarray(summaries['horizon'], dtype=float)[rows]
    generations.stages = _stages_of(record, summaries, rows)
    return generations


def _stages_of(record, summaries, rows):
    """Return the stage of each summary row: that of its told candidates (0: one stage)."""
    candidates = record.candidates
    if not len(candidates) or 'stage' not in candidates or 'told_ids' not in summaries:
        return np.zeros(len(rows), dtype=int)
    stage_of = dict(zip(np.asarray(candidates['candidate_id']).tolist(),
                        np.asarray(candidates['stage']).tolist()))
    stages = []
    for row in rows:
        told = np.asarray(summaries['told_ids'][row]).ravel().tolist()
        stages.append(int(stage_of.get(told[0], 0)) if told else 0)
    return np.asarray(stages, dtype=int)


def generations_from_evaluations(rows, weights):
    """Return Generations computed from the OK evaluations (a bag without summaries)."""
    ok = rows.ok
    generations = np.unique(rows.generation[ok])
    count = len(rows.objective_names)
    best = np.full((len(generations), count), np.nan)
    median = np.full((len(generations), count), np.nan)
    best_fitness = np.full(len(generations), np.nan)
    evaluations = np.full(len(generations), np.nan)
    so_far, told = np.inf, 0
    for index, generation in enumerate(generations):
        mask = ok & (rows.generation == generation)
        values = rows.objectives[mask]
        best[index] = values.min(axis=0)
        median[index] = np.median(values, axis=0)
        fitness = values @ weights if weights is not None else rows.fitness[mask]
        so_far = min(so_far, float(np.min(fitness)))
        told += int(mask.sum())
        best_fitness[index] = so_far
        evaluations[index] = told
    return Generations([()] * len(generations), generations, best, median, best_fitness,
                       evaluations, np.full(len(generations), np.nan), 'evaluations')


def restart_facts(restarts):
    """Return [('restarts', text)] of a run's search.restarts Restart records, or [] for none."""
    if not restarts:
        return []
    first = restarts[0]
    parts = [f'{len(restarts) - 1}; generation 0: population {first.population}']
    for restart in restarts[1:]:
        regime = ', small regime' if restart.regime == 'small' else ''
        parts.append(f'generation {restart.generation}: population {restart.population}, '
                     f'step size {restart.sigma:.3g}{regime} (after {restart.reason})')
    return [('restarts', '; '.join(parts))]


def pareto_fronts(record, num_objectives, rows):
    """Return [(order, generation, front (points, objectives))] of summary rows with a front."""
    summaries = record.generation_summaries
    fronts = []
    if not len(summaries) or 'pareto_front' not in summaries or rows is None:
        return fronts
    sizes = np.asarray(summaries['pareto_size'], dtype=np.int64)
    for order, index in enumerate(rows):
        if sizes[index] <= 0:
            continue
        values = np.asarray(summaries['pareto_front'][index], dtype=float).ravel()
        front = values[:sizes[index] * num_objectives].reshape(-1, num_objectives)
        fronts.append((order, int(summaries['generation'][index]), front))
    return fronts
