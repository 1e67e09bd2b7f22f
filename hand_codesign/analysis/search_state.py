"""
How the search itself went, generation by generation, as pycma's and pyribs's users read it.

- CMA-ES (cma, ipop-cma, bipop-cma): the step size sigma and the axis ratio, the longest over
  the shortest axis of the search distribution (the square root of C's condition number), the
  first two curves `cma.plot` draws; a restart shows as a jump back.
- MO-CMA-ES: the hypervolume each generation's front dominates (minimizing, up to a
  reference point 10 % beyond the worst value any front of the run reached in each objective).
- CMA-MAE and CMA-ME: the archive's coverage (cells filled over cells) and its QD score, the
  sum over filled cells of how far each elite's fitness lies below the median fitness of
  generation 0 (the reference CMA-MAE's threshold starts from; elites above it add nothing).

The bag holds what the search was told (GenerationSummary.told_ids and told_objectives, the
seed in RunInfo), not the optimizer's internals: the search is deterministic, so it is
replayed from them, as resume and the archive of `analyze` are, and read after each
generation. Only for a run of one optimization (no hierarchy, no two stages).
"""

import dataclasses
import pathlib

from hand_codesign.analysis import records
from hand_codesign.analysis.figures import load_pyplot
from hand_codesign.analysis.tables import float_texts, int_texts, write_csv
from hand_codesign.core.search.search import Search
from hand_codesign.core.task.parts import QD_ALGORITHMS, RESTART_ALGORITHMS
from hand_codesign.errors import UserError
import numpy as np

CMA_ALGORITHMS = ('cma', *RESTART_ALGORITHMS)
REFERENCE_MARGIN = 0.1


@dataclasses.dataclass
class SearchState:
    """Per generation: the columns of one algorithm's state; `kind` says which."""

    kind: str                 # 'cma', 'mocma' or 'qd'
    generations: np.ndarray   # (G,) generation numbers
    columns: dict             # name -> (G,) values, in the order they are written
    note: str = ''            # how a column was computed, for the report

    def write_csv(self, path):
        """Write the state as CSV: a row per generation, floats exact."""
        write_csv(path, ['generation', *self.columns], [int_texts(self.generations)] + [
            float_texts(values) for values in self.columns.values()])


def search_state(record, fronts=None):
    """
    Return the SearchState of a run, or None where it has none to show.

    record: a records.RunRecord; fronts: the fronts of an MO-CMA-ES run
    (generations.pareto_fronts: [(order, generation, front)]), read from the summaries.
    """
    try:
        task = records.run_task_of(record)
    except UserError:
        return None
    if task.hierarchy is not None or task.two_stage:
        return None
    if task.algorithm == 'mocma':
        return hypervolumes({generation: front for _, generation, front in fronts or ()})
    if task.algorithm in CMA_ALGORITHMS or task.algorithm in QD_ALGORITHMS:
        return replayed_state(task, records.told_answers(record))
    return None


def hypervolumes(fronts):
    """Return the hypervolume of each generation's front, one reference point for all."""
    fronts = {generation: np.asarray(front, dtype=float)
              for generation, front in sorted(dict(fronts).items()) if len(front)}
    if not fronts:
        return None
    worst = np.max([front.max(axis=0) for front in fronts.values()], axis=0)
    reference = worst + REFERENCE_MARGIN * np.maximum(np.abs(worst), 1e-12)
    values = [dominated_volume(front, reference) for front in fronts.values()]
    return SearchState('mocma', np.array(list(fronts)), {'hypervolume': np.array(values)},
                       'reference point: ' + ', '.join(f'{value:.4g}' for value in reference))


def dominated_volume(points, reference):
    """
    Return the volume that points (N, D) dominate below reference (D,), minimizing.

    Slices along the last objective (the HSO scheme): exact, fine for the fronts of a run.
    """
    points = points[np.all(points < reference, axis=1)]
    if not len(points):
        return 0.0
    if points.shape[1] == 1:
        return float(reference[0] - points[:, 0].min())
    order = points[np.argsort(points[:, -1], kind='stable')]
    volume = 0.0
    for index, point in enumerate(order):
        top = order[index + 1, -1] if index + 1 < len(order) else reference[-1]
        if top > point[-1]:
            volume += (top - point[-1]) * dominated_volume(order[:index + 1, :-1],
                                                           reference[:-1])
    return volume


def replayed_state(task, told):
    """Replay a CMA-ES or quality-diversity search from what it was told; read each generation."""
    search = Search(task)
    generations, readings, reference = [], [], None
    while not search.stop():
        candidates = search.ask()
        if not candidates or not all(c.candidate_id in told for c in candidates):
            break
        answers = {c.candidate_id: told[c.candidate_id] for c in candidates}
        search.tell(answers)
        optimizer = search.optimizer
        if reference is None and task.algorithm in QD_ALGORITHMS:
            reference = float(np.median([optimizer.fitness_of(getattr(value, 'objectives',
                                                                      value))
                                         for value in answers.values()]))
        generations.append(candidates[0].generation)
        readings.append(cma_reading(optimizer) if reference is None
                        else qd_reading(optimizer, reference))
    if not readings:
        return None
    names = list(readings[0])
    columns = {name: np.array([reading[name] for reading in readings]) for name in names}
    kind = 'qd' if reference is not None else 'cma'
    note = (f"QD score against generation 0's median fitness, {reference:.6g}"
            if reference is not None else '')
    return SearchState(kind, np.array(generations), columns, note)


def cma_reading(optimizer):
    """Return sigma and the axis ratio of a CmaEs (or of a restart strategy's current one)."""
    es = getattr(optimizer, '_instance', optimizer)._es
    axes = np.asarray(es.sm.D, dtype=float)
    return {'sigma': float(es.sigma), 'axis_ratio': float(axes.max() / axes.min())}


def qd_reading(optimizer, reference):
    """Return coverage and QD score of a quality-diversity optimizer's archive."""
    grid = optimizer.fitness_grid()
    filled = grid[np.isfinite(grid)]
    return {'coverage': len(filled) / grid.size,
            'qd_score': float(np.clip(reference - filled, 0.0, None).sum()),
            'elites': float(len(filled))}


LABELS = {'sigma': 'step size sigma', 'axis_ratio': 'axis ratio (longest / shortest axis)',
          'hypervolume': 'hypervolume of the front', 'coverage': 'coverage (cells filled)',
          'qd_score': 'QD score', 'elites': 'elites'}
LOG_SCALED = ('sigma', 'axis_ratio')


def plot_search_state(path, state, title, restarts=()):
    """Plot a SearchState: one panel per quantity (not elites), over the generations."""
    pyplot = load_pyplot()
    names = [name for name in state.columns if name != 'elites']
    figure, axes = pyplot.subplots(1, len(names), figsize=(4.6 * len(names), 3.4),
                                   squeeze=False)
    for ax, name in zip(axes.flat, names):
        values = state.columns[name]
        ax.plot(state.generations, values, color='tab:blue', marker='.' if len(values) < 30
                else None)
        if name in LOG_SCALED and np.all(values > 0):
            ax.set_yscale('log')
        for restart in restarts[1:]:
            ax.axvline(restart.generation - 0.5, color='tab:red', linestyle='--',
                       linewidth=0.8)
        ax.set_title(LABELS[name], fontsize='medium')
        ax.set_xlabel('generation')
        ax.xaxis.get_major_locator().set_params(integer=True)
        ax.grid(True, alpha=0.3)
    figure.suptitle(f'search state of {title}' if title else 'search state',
                    fontsize='medium')
    figure.tight_layout()
    figure.savefig(path, dpi=100)
    pyplot.close(figure)
    return pathlib.Path(path)
