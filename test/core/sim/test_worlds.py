"""World states: seeded, uniform in the task's ranges, and the robustness grid."""

import math
import pathlib

from hand_codesign.core import grid_world_states, load_task, world_states, WorldState
from hand_codesign.core.experiments.measures import unseen_world_states
from hand_codesign.core.sim.objectives import orientation_angle
from hand_codesign.core.sim.worlds import object_state, randomized_quantities
from hand_codesign.core.task import resting_height
import numpy as np
import pytest

TASKS = pathlib.Path(__file__).resolve().parents[3] / 'config' / 'tasks'


def as_rows(worlds):
    return np.array([[*w.position_delta, w.orientation_delta, w.friction_delta, w.scale,
                      w.mass_factor] for w in worlds])


@pytest.mark.parametrize('name', ['task1', 'task3', 'task4', 'task6'])
def test_worlds_lie_in_their_ranges(name):
    task = load_task(TASKS / f'{name}.yaml').replace(num_world_states=200)
    rows = as_rows(world_states(task))
    assert rows.shape == (200, 7)
    for column, (quantity, bounds) in enumerate(task.randomization.quantities()):
        assert (rows[:, column] >= bounds.lower).all(), quantity
        assert (rows[:, column] <= bounds.upper).all(), quantity
        if bounds.width > 0:  # uniform: spread over the range, not stuck at one end
            assert rows[:, column].std() > bounds.width / 5, quantity


def test_same_seed_same_worlds_other_seed_other_worlds():
    task = load_task(TASKS / 'task5.yaml')
    assert world_states(task) == world_states(load_task(TASKS / 'task5.yaml'))
    assert world_states(task) != world_states(task.replace(seed=1))
    assert len(world_states(task)) == task.num_world_states == 8
    # the first worlds of a larger set are the worlds of a smaller one
    assert world_states(task.replace(num_world_states=64))[:8] == world_states(task)


def test_grid_of_task4_has_15625_worlds():
    task = load_task(TASKS / 'task4.yaml')
    assert randomized_quantities(task) == ['position_x', 'position_y', 'orientation',
                                           'friction', 'scale', 'mass']
    grid = grid_world_states(task, values_per_quantity=5)
    assert len(grid) == 5 ** 6 == 15625
    rows = as_rows(grid)
    assert sorted(set(rows[:, 3])) == pytest.approx(list(np.linspace(-0.35, 0.35, 5)))
    assert set(rows[:, 2]) == {0.0}
    assert len({tuple(row) for row in rows}) == 15625


def test_object_on_the_plane_rests_on_it():
    task = load_task(TASKS / 'task6.yaml')
    world = WorldState((0.004, -0.002, 0.0), 0.3, 0.05, 2.0, 1.5)
    state = object_state(task, world)
    assert state.position[:2] == pytest.approx((0.004, -0.002))
    assert state.position[2] == pytest.approx(0.04)  # an 8 cm box turned about z
    assert state.size == pytest.approx((0.08, 0.08, 0.08))
    assert state.mass == pytest.approx(0.045) and state.friction == pytest.approx(0.35)
    assert orientation_angle(state.orientation, (0, 0, 0, 1)) == pytest.approx(0.3)
    turned = object_state(task, WorldState.nominal())
    assert turned.position == pytest.approx(task.object_spec.position)


def test_resting_height_of_a_tilted_box_and_capsule():
    box = load_task(TASKS / 'task5.yaml').object_spec
    tilted = (math.sin(math.pi / 8), 0.0, 0.0, math.cos(math.pi / 8))  # 45 deg about x
    assert resting_height(box, 1.0, tilted) == pytest.approx(0.02 * math.sqrt(2))
    capsule = load_task(TASKS / 'task3.yaml').object_spec  # lying along x
    assert resting_height(capsule) == pytest.approx(0.02)
    assert resting_height(capsule, 1.0, (0, 0, 0, 1)) == pytest.approx(0.02 + 0.075)


def test_midair_object_moves_by_its_delta():
    task = load_task(TASKS / 'task3.yaml')
    world = world_states(task)[0]
    state = object_state(task, world)
    expected = np.array(task.object_spec.position) + world.position_delta
    assert state.position == pytest.approx(tuple(expected))
    assert state.size == pytest.approx((0.02 * world.scale, 0.15 * world.scale))


@pytest.mark.parametrize('seed', [0, 1, 7, 21])
def test_resampled_draws_differ_per_generation_and_from_every_other_stream(seed):
    task = load_task(TASKS / 'task5.yaml').replace(seed=seed)
    draws = [world_states(task.replace(world_draw=k)) for k in (1, 2, 3)]
    assert world_states(task.replace(world_draw=2)) == draws[1]  # a pure function of (seed, k)
    assert all(len(draw) == task.num_world_states for draw in draws)
    others = {'fixed': world_states(task), 'held out': world_states(task.replace(held_out=True)),
              'unseen': unseen_world_states(task, task.num_world_states)}
    sets = {f'draw {k}': draw for k, draw in zip((1, 2, 3), draws)}
    sets.update(others)
    rows = {name: as_rows(worlds) for name, worlds in sets.items()}
    names = sorted(rows)
    for index, first in enumerate(names):
        for second in names[index + 1:]:
            # continuous draws: no world of one stream is a world of another
            assert not np.isin(rows[first][:, 0], rows[second][:, 0]).any(), (first, second)
    # another seed draws other worlds for the same generation
    assert world_states(task.replace(seed=seed + 100, world_draw=1)) != draws[0]
    # the first worlds of a larger draw are those of a smaller one, as for the fixed set
    assert world_states(task.replace(world_draw=2, num_world_states=20))[:8] == draws[1]
    # stage 1 of a two-stage task stays on the nominal world, whatever the draw
    assert world_states(task.replace(two_stage=True, stage=1, world_draw=3)) == [
        WorldState.nominal()]
