"""The per-generation statistics the optimizer publishes and the terminal line it prints."""

from hand_codesign.core.run.summary import generation_summary
from hand_codesign.core.run.summary import progress_line
from hand_codesign.core.search.optimizers import OptimizerResult
import numpy as np

NAMES = ('position_1', 'orientation_1')


def result(front=None):
    extra = {} if front is None else {'pareto_objectives': np.asarray(front, dtype=float)}
    return OptimizerResult(candidate_id=7, generation=1, x=np.array([0.25, 0.5]),
                           objectives=np.array([0.5, 0.25]), fitness=0.525, evaluations=8,
                           iterations=2, **extra)


def test_statistics_are_per_objective_over_the_told_batch():
    told = [[3.0, 0.1], [1.0, 0.4], [2.0, 0.2], [5.0, 0.3]]
    summary = generation_summary(1, (2, 2), NAMES, [4, 5, 6, 7], told, result(), 8, 2.5)
    assert summary['best'].tolist() == [1.0, 0.1]
    assert summary['median'].tolist() == [2.5, 0.25]
    assert summary['worst'].tolist() == [5.0, 0.4]
    assert summary['told_ids'] == [4, 5, 6, 7]
    assert summary['told_objectives'].shape == (4, 2)
    assert summary['structure'] == (2, 2) and summary['check'] is False
    assert (summary['best_id'], summary['best_fitness']) == (7, 0.525)
    assert summary['pareto_front'].shape == (0, 2)
    assert summary['final'] is False and summary['stop_reason'] == ''


def test_a_pareto_front_is_kept_row_by_row():
    front = [[0.5, 0.25], [0.25, 0.5], [0.1, 0.9]]
    summary = generation_summary(0, (1,), NAMES, [0], [[0.5, 0.25]], result(front), 1, 0.1,
                                 check=True)
    assert summary['pareto_front'].tolist() == front and summary['check'] is True


def test_the_progress_line_says_where_the_run_is():
    summary = generation_summary(1, (2, 2), NAMES, [4], [[1.0, 0.1]], result(), 8, 2.5)
    line = progress_line(summary, 10, 3.2, 41.6)
    assert line.startswith('generation 2/10 [2x2] | 8 evaluations, 3.2/s | best fitness 0.525')
    assert '(position_1 0.5, orientation_1 0.25)' in line and line.endswith('about 42 s left')
    # a long run's time left in hours and minutes, not raw seconds
    assert progress_line(summary, 10, 3.2, 5400.0).endswith('about 1 h 30 min left')
    assert progress_line(summary, 10, 3.2, 754.0).endswith('about 12 min left')
    assert progress_line(summary, 10, 0.0, None).endswith('| time left not known yet')
