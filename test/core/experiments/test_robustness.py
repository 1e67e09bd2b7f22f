"""Robustness evaluation of a final design on a grid of world states (Fig. 3's data)."""

import csv
import pathlib

from hand_codesign.core import grid_world_states, load_task, world_states, WorldState
from hand_codesign.core.evaluate import evaluate
from hand_codesign.core.experiments.robustness import evaluate_robustness
from hand_codesign.core.sim.objectives import orientation_angle, position_distance
from hand_codesign.core.sim.worlds import object_state
from hand_codesign.core.task.genome import genome_spec
import numpy as np
import pytest

TASK5 = pathlib.Path(__file__).resolve().parents[3] / 'config' / 'tasks' / 'task5.yaml'
TASK3 = TASK5.with_name('task3.yaml')


def test_paper_grid_has_5_values_on_each_of_6_quantities():
    task = load_task(TASK5)
    assert len(grid_world_states(task, 5)) == 15625


@pytest.mark.system
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
    assert np.array_equal(report.final_poses[1], report.start_poses[1])  # not simulated


def test_worlds_csv_recomputes_the_errors_from_its_poses(tmp_path):
    """The start, goal and final poses in worlds.csv give its errors with eq. 3 and 4."""
    task = load_task(TASK3)  # goals relative to each world's start: every world's goal differs
    x = genome_spec(task).initial_mean()
    worlds = world_states(task, 3)
    report = evaluate_robustness(x, task, worlds=worlds)
    direct = evaluate(x, task, worlds=worlds)
    assert np.array_equal(report.final_poses, direct.final_poses)
    report.write_csv(tmp_path / 'worlds.csv')
    with open(tmp_path / 'worlds.csv', newline='', encoding='utf-8') as stream:
        rows = list(csv.DictReader(stream))
    assert len(rows) == 3

    def pose(row, when):
        return (np.array([float(row[f'{when}_position_{axis}']) for axis in 'xyz']),
                np.array([float(row[f'{when}_orientation_{axis}']) for axis in 'xyzw']))

    for row, world in zip(rows, worlds):
        start, goal, final = pose(row, 'start'), pose(row, 'goal'), pose(row, 'final')
        state = object_state(task, world)
        assert start[0].tolist() == list(state.position)
        assert start[1].tolist() == list(state.orientation)
        for when, (position, orientation) in (('initial', start), ('final', final)):
            assert float(row[f'{when}_position_error']) == pytest.approx(
                position_distance(position, goal[0], task.goals.distance), abs=1e-12)
            assert float(row[f'{when}_orientation_error']) == pytest.approx(
                orientation_angle(orientation, goal[1]), abs=1e-6)
        assert not np.allclose(final[0], start[0])  # the object moved
    goals = [pose(row, 'goal')[0] for row in rows]
    assert not np.allclose(goals[0], goals[1])  # each world's goal moved with its start
