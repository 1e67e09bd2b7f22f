"""A campaign's figures: median and interquartile band across seeds, any of three formats."""

from hand_codesign import cli
from hand_codesign.campaign import figures
import numpy as np
import pytest


def test_the_band_is_the_seeds_percentiles_of_their_best_so_far():
    curves = [(1, ([10, 20, 30], [5.0, 4.0, 1.0])),
              (2, ([10, 20], [3.0, 2.0])),          # ended early: its 2.0 holds after 20
              (3, ([20, 30], [9.0, 6.0])),          # told first at 20
              (4, ([], []))]                        # not run (yet): left out
    grid, low, median, high = figures.seed_band(curves)
    assert grid.tolist() == [10, 20, 30]
    assert median.tolist() == [4.0, 4.0, 2.0]     # at 10: seeds 1, 2; then all three
    assert low.tolist() == [np.percentile([5, 3], 25), 3.0, 1.5]
    assert high.tolist() == [np.percentile([5, 3], 75), 6.5, 4.0]


@pytest.mark.parametrize('suffix, start', [('png', b'\x89PNG'), ('svg', b'<?xml'),
                                           ('pdf', b'%PDF')])
def test_convergence_figure_is_written_in_the_format_asked(tmp_path, suffix, start):
    panels = [('cma (CMA-ES)', [(seed, (np.arange(1, 6) * 10.0, np.geomspace(1, 0.1, 5) * seed))
                                for seed in (1, 2, 3)]),
              ('mocma (MO-CMA-ES)', [(1, (np.arange(1, 4) * 20.0, np.array([2.0, 1.0, 0.5])))])]
    path = tmp_path / f'convergence.{suffix}'
    figures.plot_convergence(path, panels, 'tiny')
    assert path.read_bytes().startswith(start)


def test_reproduce_takes_the_figure_format():
    parser = cli.build_parser()
    assert parser.parse_args(['reproduce', 'task5-joint-limits', '--format', 'svg']).format == (
        'svg')
    assert parser.parse_args(['reproduce', 'task5-joint-limits']).format == 'png'
    with pytest.raises(SystemExit):
        parser.parse_args(['reproduce', 'task5-joint-limits', '--format', 'tiff'])
