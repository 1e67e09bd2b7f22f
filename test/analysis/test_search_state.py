"""
`analyze`'s view of the search itself, and its figures in PNG, SVG or PDF.

CMA-ES's step size and axis ratio, MO-CMA-ES's hypervolume, the archive's coverage and QD
score, each per generation.
"""

import csv
import itertools

from analysis_run import run_cli
from hand_codesign.analysis import records
from hand_codesign.analysis.search_state import dominated_volume
import moocore
import numpy as np
import pytest
from task_files import optimizer_document, write_task

BUDGET = ['--iterations', '4', '--population', '6', '--world-states', '2', '--seed', '3',
          '--domain-id', 'auto', '--quiet']


@pytest.fixture(scope='module')
def bags(tmp_path_factory):
    """Return {algorithm: bag} of three short real runs."""
    folder = tmp_path_factory.mktemp('search_state')
    found = {}
    for algorithm in ('cma', 'mocma', 'cma-mae'):
        task = write_task(folder, optimizer_document(algorithm), f'{algorithm}.yaml')
        bag = folder / algorithm
        result = run_cli('run', '--task', task, '--bag', bag, '--evaluators', '1', *BUDGET)
        assert result.returncode == 0, result.stderr
        found[algorithm] = bag
    return found


def analyzed(bag, out, *flags):
    result = run_cli('analyze', bag, '--out', out, *flags)
    assert result.returncode == 0, result.stderr
    with open(out / 'search_state.csv', newline='') as stream:
        rows = list(csv.DictReader(stream))
    return {name: np.array([float(row[name]) for row in rows]) for name in rows[0]}


@pytest.mark.system
@pytest.mark.parametrize('suffix', ['svg', 'pdf'])
def test_cma_es_step_size_and_axis_ratio_per_generation(bags, tmp_path, suffix):
    state = analyzed(bags['cma'], tmp_path / 'report', '--format', suffix)
    figures = sorted(path.name for path in (tmp_path / 'report').glob(f'*.{suffix}'))
    assert figures == [f'best_design.{suffix}', f'convergence.{suffix}',
                       f'search_state.{suffix}']
    assert not list((tmp_path / 'report').glob('*.png'))
    assert (tmp_path / 'report' / f'search_state.{suffix}').read_bytes()[:5] in (
        b'<?xml', b'%PDF-')
    assert list(state['generation']) == [0, 1, 2, 3]
    # pycma's own numbers of the search as the run left it, replayed independently
    es = records.replayed_optimizer(records.open_run(bags['cma']), ('cma',))._es
    assert state['sigma'][-1] == es.sigma
    assert state['axis_ratio'][-1] == es.sm.D.max() / es.sm.D.min() >= 1.0
    assert np.all(state['sigma'] > 0)


@pytest.mark.system
def test_mo_cma_es_hypervolume_per_generation(bags, tmp_path):
    state = analyzed(bags['mocma'], tmp_path / 'report')
    assert list(state['generation']) == [0, 1, 2, 3]
    # an elitist (mu + lambda) front never loses volume against one reference point
    assert np.all(np.diff(state['hypervolume']) >= 0) and state['hypervolume'][-1] > 0


@pytest.mark.system
def test_quality_diversity_coverage_and_qd_score(bags, tmp_path):
    state = analyzed(bags['cma-mae'], tmp_path / 'report')
    archive = records.archive_of(records.open_run(bags['cma-mae']))
    grid = archive.fitness_grid()
    assert state['coverage'][-1] == np.isfinite(grid).sum() / grid.size
    assert state['elites'][-1] == np.isfinite(grid).sum()
    assert np.all(np.diff(state['elites']) >= 0) and np.all(state['qd_score'] >= 0)


@pytest.mark.parametrize('dimensions', [2, 3, 4])
def test_the_hypervolume_agrees_with_moocore(dimensions):
    generator = np.random.default_rng(dimensions)
    for points in (5, 30):
        front = generator.uniform(0, 1, (points, dimensions))
        reference = np.full(dimensions, 1.1)
        assert dominated_volume(front, reference) == pytest.approx(
            moocore.hypervolume(front, ref=reference), rel=1e-12)


def test_the_hypervolume_of_boxes_by_hand():
    assert dominated_volume(np.array([[1.0, 1.0]]), np.array([3.0, 2.0])) == 2.0
    corners = np.array(list(itertools.product([1.0, 2.0], repeat=2)))
    assert dominated_volume(corners, np.array([3.0, 3.0])) == 4.0
    assert dominated_volume(np.array([[4.0, 0.0]]), np.array([3.0, 3.0])) == 0.0
