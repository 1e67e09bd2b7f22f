"""Eq. (1)'s PD law stepped in C on MuJoCo: the bits of the law in Python, or that law itself."""

import ctypes
import dataclasses
import pathlib

from hand_codesign.core import genome_spec, load_task
from hand_codesign.core.evaluate import evaluate_design
from hand_codesign.core.sim import mujoco_native
from hand_codesign.core.sim.mujoco_sim import MujocoSimulator
import mujoco
import numpy as np
import pytest

TASKS = pathlib.Path(__file__).resolve().parents[3] / 'config' / 'tasks'


def on_mujoco(task):
    return task.replace(physics=dataclasses.replace(task.physics, engine='mujoco'))


def simulated_designs(task, count, seed=1):
    """Return `count` designs around the search's start that do not start in collision."""
    spec = genome_spec(task)
    generator = np.random.default_rng(seed)
    designs = []
    with MujocoSimulator() as simulator:
        while len(designs) < count:
            x = np.clip(spec.initial_mean() + 0.15 * generator.normal(size=spec.size), 0, 1)
            design = spec.decode(x)
            if not evaluate_design(design, task, simulator=simulator).collision:
                designs.append(design)
    return designs


@pytest.mark.skipif(mujoco_native.library() is None,
                    reason=f'no C compiler here: {mujoco_native.unavailable_reason()}')
@pytest.mark.parametrize('preset', ['task5_pd.yaml', 'task1.yaml'])
def test_the_law_in_c_gives_the_bits_of_the_law_in_python(preset):
    task = on_mujoco(load_task(TASKS / preset).replace(num_world_states=2))
    with MujocoSimulator() as native, MujocoSimulator() as python:
        python.native = False
        for design in simulated_designs(task, 3):
            fast, slow = (evaluate_design(design, task, simulator=simulator)
                          for simulator in (native, python))
            assert fast.simulated_time > 0
            np.testing.assert_array_equal(fast.world_objectives, slow.world_objectives)
            np.testing.assert_array_equal(fast.final_poses, slow.final_poses)


@pytest.mark.skipif(mujoco_native.library() is None,
                    reason=f'no C compiler here: {mujoco_native.unavailable_reason()}')
def test_the_c_loop_steps_without_the_profiler_and_gives_its_clock_back():
    clock = ctypes.c_void_p.in_dll(ctypes.CDLL(str(mujoco_native._mujoco_paths()[1])),
                                   'mjcb_time')
    task = on_mujoco(load_task(TASKS / 'task5_pd.yaml').replace(num_world_states=1))
    design = simulated_designs(task, 1)[0]
    step = mujoco.mjtTimer.mjTIMER_STEP
    with MujocoSimulator() as simulator:
        evaluate_design(design, task, simulator=simulator)
        installed = clock.value  # the bindings' clock, installed with the first MjData
        evaluate_design(design, task, simulator=simulator)
        d = simulator.mj_data
        assert installed and clock.value == installed
        assert d.timer[step].number > 0 and d.timer[step].duration == 0
        mujoco.mj_step(simulator.mj_model, d)
        assert d.timer[step].duration > 0


def test_without_a_compiler_the_law_steps_in_python(tmp_path, monkeypatch):
    task = on_mujoco(load_task(TASKS / 'task5_pd.yaml').replace(num_world_states=1))
    design = simulated_designs(task, 1)[0]
    expected = evaluate_design(design, task)
    monkeypatch.setattr(mujoco_native, 'COMPILER', str(tmp_path / 'no-such-cc'))
    monkeypatch.setattr(mujoco_native, 'CACHE', tmp_path / 'cache')
    monkeypatch.setattr(mujoco_native, '_LOADED', {})
    assert mujoco_native.library() is None and mujoco_native.unavailable_reason()
    with MujocoSimulator() as simulator:
        fallback = evaluate_design(design, task, simulator=simulator)
    np.testing.assert_array_equal(fallback.world_objectives, expected.world_objectives)


def test_the_law_is_compiled_once_into_the_cache(tmp_path, monkeypatch):
    monkeypatch.setattr(mujoco_native, 'CACHE', tmp_path)
    monkeypatch.setattr(mujoco_native, '_LOADED', {})
    if mujoco_native.library() is None:
        pytest.skip(f'no C compiler here: {mujoco_native.unavailable_reason()}')
    built = sorted(path.name for path in tmp_path.iterdir())
    assert len(built) == 1 and built[0].startswith('mujoco_pd-') and built[0].endswith('.so')
