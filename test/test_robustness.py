"""Robustness evaluation of a final design on a grid of world states (Fig. 3's data)."""

import csv
import pathlib

from hand_codesign.core import grid_world_states, load_task, WorldState
from hand_codesign.core.evaluate import evaluate
from hand_codesign.core.genome import genome_spec
from hand_codesign.core.robustness import evaluate_robustness
import numpy as np

TASK5 = pathlib.Path(__file__).resolve().parents[1] / 'config' / 'tasks' / 'task5.yaml'


def test_paper_grid_has_5_values_on_each_of_6_quantities():
    task = load_task(TASK5)
    assert len(grid_world_states(task, 5)) == 15625


def test_grid_report_is_the_same_serially_and_with_two_processes(tmp_path):
    task = load_task(TASK5)
    x = genome_spec(task).initial_mean()
    worlds = grid_world_states(task, 2)  # 64 worlds
    serial = evaluate_robustness(x, task, worlds=worlds, chunk_size=16)
    pooled = evaluate_robustness(x, task, worlds=worlds, processes=2, chunk_size=24)
    direct = evaluate(x, task, worlds=worlds)

    assert serial.size == 64
    for report in (serial, pooled):
        assert np.array_equal(report.initial_errors, direct.initial_errors)
        assert np.array_equal(report.final_errors, direct.final_errors)
        assert not report.collisions.any()
    # The box starts 1 cm (plus the randomized offset) from the goal and the hand moves it.
    assert np.all(serial.initial_errors[:, 0] > 0.004)
    assert not np.array_equal(serial.final_errors, serial.initial_errors)
    summary = serial.summary()
    assert summary['final']['position']['max'] == np.max(serial.final_errors[:, 0])
    assert 0.0 <= serial.success_rate(0.01, np.pi) <= 1.0

    serial.write_csv(tmp_path / 'robustness.csv')
    rows = list(csv.DictReader(open(tmp_path / 'robustness.csv')))
    assert len(rows) == 64
    assert float(rows[5]['final_position_error']) == serial.final_errors[5, 0]
    assert float(rows[5]['scale']) == worlds[5].scale


def test_worlds_in_collision_are_found_one_by_one():
    task = load_task(TASK5)
    x = genome_spec(task).initial_mean()
    nominal = WorldState.nominal()
    huge = WorldState((0.0, 0.0, 0.0), 0.0, 0.0, 4.0, 1.0)  # a 16 cm box hits the fingers
    shifted = WorldState((0.004, 0.0, 0.0), 0.1, 0.0, 1.0, 1.0)
    report = evaluate_robustness(x, task, worlds=[nominal, huge, shifted])

    assert report.collisions.tolist() == [False, True, False]
    alone = evaluate(x, task, worlds=[nominal, shifted])
    assert np.array_equal(report.final_errors[[0, 2]], alone.final_errors)
    assert np.array_equal(report.final_errors[1], report.initial_errors[1])
