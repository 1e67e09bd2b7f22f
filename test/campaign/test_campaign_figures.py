"""A campaign's figures: median and interquartile band across seeds, any of three formats."""

import types

from hand_codesign import cli
from hand_codesign.campaign import figures
import matplotlib
import numpy as np
from PIL import Image
import pytest

THIRTY = [f'configuration-{index:02d}-named-in-full' for index in range(30)]


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


def thirty_panels():
    generator = np.random.default_rng(0)
    return [(label, [(seed, (np.arange(1, 21) * 16.0, np.minimum.accumulate(
        generator.uniform(0.1, 2.0, 20)))) for seed in (1, 2, 3)]) for label in THIRTY]


def thirty_groups():
    generator = np.random.default_rng(1)
    return [(label, [{'worlds': {'initial_errors': {'position': generator.uniform(0, .02, 50)},
                                 'errors': {'position': generator.uniform(0, .01, 50)}}}])
            for label in THIRTY]


TOLERANCE = types.SimpleNamespace(kind='position', limit=0.005, describe=lambda: '5 mm')


@pytest.mark.parametrize('figure', ['convergence', 'errors'])
def test_thirty_configurations_stay_legible(tmp_path, figure):
    """Every name written once, in a page-sized figure, not a strip thousands of pixels wide."""
    draw = {'convergence': lambda path: figures.plot_convergence(path, thirty_panels(), 't'),
            'errors': lambda path: figures.plot_errors(path, thirty_groups(), TOLERANCE, 't')}
    draw[figure](tmp_path / 'figure.png')
    width, height = Image.open(tmp_path / 'figure.png').size
    assert width <= 1600 and height <= 1600 and width / height < 3
    with matplotlib.rc_context({'svg.fonttype': 'none'}):   # text as text, to be read
        draw[figure](tmp_path / 'figure.svg')
    text = (tmp_path / 'figure.svg').read_text()
    assert all(text.count(f'>{label}<') == 1 for label in THIRTY)


def test_up_to_ten_configurations_share_one_axis_in_ten_colours(tmp_path):
    with matplotlib.rc_context({'svg.fonttype': 'none'}):
        figures.plot_convergence(tmp_path / 'ten.svg', thirty_panels()[:10], 't')
    text = (tmp_path / 'ten.svg').read_text()
    assert all(f'{label}: median of 3 seeds' in text for label in THIRTY[:10])
