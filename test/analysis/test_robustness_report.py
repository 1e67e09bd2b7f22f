"""`hand-codesign robustness`: the best design on a grid or sample of worlds, Fig. 3 and tables."""

import csv

from analysis_run import ROOT
from analysis_run import run_codesign
from analysis_run import TASK
from hand_codesign.analysis.records import recorded_design
from hand_codesign.analysis.records import run_task_of
from hand_codesign.analysis.records import structure_bests
from hand_codesign.analysis.robustness_report import robustness_worlds
from hand_codesign.bag.reader import read_run
from hand_codesign.cli import main
from hand_codesign.core.evaluate import evaluate
from hand_codesign.core.run.runs import run_task
from hand_codesign.core.sim.worlds import grid_world_states
from hand_codesign.core.task.variant import Variant
import numpy as np
import pytest

pytestmark = pytest.mark.system


def read_csv(path):
    with open(path, newline='', encoding='utf-8') as stream:
        return list(csv.DictReader(stream))


def test_grid_of_the_best_design_on_two_processes(real_run, tmp_path, capsys):
    out = tmp_path / 'robustness'
    assert main(['robustness', str(real_run.bag), '--samples', '64', '--workers', '2',
                 '--out', str(out)]) == 0
    printed = capsys.readouterr().out
    assert 'on 64 world states (grid of 2 values on each of 6 randomized quantities' in printed
    assert 'with 2 processes' in printed
    for row in ('initial position', 'initial orientation', 'final position',
                'final orientation'):
        assert row in printed
    worlds = read_csv(out / 'worlds.csv')
    assert len(worlds) == 64
    task = run_task(TASK.read_text(), str(TASK), 3, 4, 6, 2)
    grid = grid_world_states(task, 2)
    assert [float(row['scale']) for row in worlds] == [world.scale for world in grid]
    percentiles = read_csv(out / 'percentiles.csv')
    assert [row['error'] for row in percentiles] == [
        'initial_position', 'initial_orientation', 'final_position', 'final_orientation']
    final_position = np.array([float(row['final_position_error']) for row in worlds])
    assert float(percentiles[2]['p50']) == np.percentile(final_position, 50)
    assert (out / 'robustness.png').read_bytes().startswith(b'\x89PNG')
    # a world of the grid, evaluated alone, ends where the report says
    best = recorded_design(read_run(real_run.bag), real_run.result['best_candidate_id'])
    alone = evaluate(best.x, task, worlds=[grid[5]])
    assert float(worlds[5]['final_position_error']) == alone.final_errors[0, 0]
    assert worlds[5]['collision'] == str(int(alone.collision))
    final = [float(worlds[5][f'final_position_{axis}']) for axis in 'xyz'] + \
        [float(worlds[5][f'final_orientation_{axis}']) for axis in 'xyzw']
    assert final == alone.final_poses[0].tolist()


def test_a_count_that_is_no_grid_draws_seeded_worlds(real_run, tmp_path, capsys):
    out = tmp_path / 'robustness'
    assert main(['robustness', str(real_run.bag), '--samples', '10', '--workers', '1',
                 '--out', str(out)]) == 0
    assert 'uniform in the ranges of the task' in capsys.readouterr().out
    assert len(read_csv(out / 'worlds.csv')) == 10
    task = run_task(TASK.read_text(), str(TASK), 3, 4, 6, 2)
    first, _ = robustness_worlds(task, 10)
    again, _ = robustness_worlds(task, 10)
    assert first == again


def test_bad_sample_count(real_run, capsys):
    assert main(['robustness', str(real_run.bag), '--samples', '0']) == 2
    assert '--samples: expected a positive number' in capsys.readouterr().err


def test_fig3_per_structure_of_a_hierarchy_run(tmp_path, capsys):
    text = (ROOT / 'config' / 'tasks' / 'task4.yaml').read_text()
    text = text.replace('stop_structure: [2, 3]', 'stop_structure: [1, 1]')
    text = text.replace('evaluation_world_states: 128', 'evaluation_world_states: 2')
    task_file = tmp_path / 'task4_small.yaml'
    task_file.write_text(text)
    bag = tmp_path / 'hierarchy'
    run_codesign(bag, ['--iterations', '1', '--population', '4', '--world-states', '2',
                       '--seed', '1'], task=task_file)
    record = read_run(bag)
    bests = structure_bests(record)
    # (1) -> (1, 1) (the stop structure bounds fingers to one joint), then a third finger
    assert [structure for structure, _ in bests] == [(1,), (1, 1), (1, 1, 1)]
    out = tmp_path / 'fig3'
    assert main(['robustness', str(bag), '--samples', '64', '--workers', '2',
                 '--out', str(out)]) == 0
    printed = capsys.readouterr().out
    assert printed.count('on 64 world states (grid of 2 values') == len(bests)
    rows = read_csv(out / 'structures.csv')
    assert [row['structure'] for row in rows[::4]] == ['1', '1 1', '1 1 1']
    assert (out / 'structures.png').read_bytes().startswith(b'\x89PNG')
    for structure, candidate_id in bests:
        folder = out / ('structure_' + '_'.join(map(str, structure)))
        worlds = read_csv(folder / 'worlds.csv')
        assert len(worlds) == 64
        # the structure's best design, evaluated alone on a grid world, ends as reported
        design = recorded_design(record, candidate_id)
        task = run_task_of(record, Variant(structure=tuple(structure)))
        alone = evaluate(design.x, task, worlds=[grid_world_states(task, 2)[9]])
        assert float(worlds[9]['final_position_error']) == alone.final_errors[0, 0]
        median = next(row for row in rows if row['structure'] == ' '.join(map(str, structure))
                      and row['error'] == 'final_position')
        final = [float(row['final_position_error']) for row in worlds]
        assert float(median['p50']) == np.percentile(final, 50)
