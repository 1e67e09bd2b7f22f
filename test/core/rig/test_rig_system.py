"""
Hardware in the loop over DDS: a run scored by a rig evaluator on a simulated rig.

A small Task 1 run (trajectory goals: a check every 0.1 s) with `--rig sim` and no simulation
evaluator: the rig publishes every physics step and every objective is the one `evaluate`
computes, exactly. Then `hand-codesign evaluate BAG --rig sim` at 100 Hz, the samples halfway
between the checks' physics steps: prediction and measurement of the best designs sit side by
side in the new bag, within the interpolation tolerance derived from the recorded traces
(core.rig.trials), and `analyze` reports the gap.
"""

import pathlib
import subprocess
import sys

from hand_codesign.analysis.records import design_task, recorded_design, run_task_of
from hand_codesign.analysis.rig_report import rig_comparison
from hand_codesign.analysis.rig_traces import trial_traces
from hand_codesign.bag.reader import read_run
from hand_codesign.core import evaluate
from hand_codesign.core.rig.trials import interpolation_tolerance
from hand_codesign.core.sim.objectives import goal_schedule
import numpy as np
import pytest

pytestmark = pytest.mark.system

ROOT = pathlib.Path(__file__).resolve().parents[3]
TASK = ROOT / 'config' / 'tasks' / 'task1.yaml'
BUDGET = ['--iterations', '2', '--population', '4', '--world-states', '2', '--seed', '7']


def command(*arguments, timeout=300):
    process = subprocess.run([sys.executable, '-m', 'hand_codesign.cli', *map(str, arguments)],
                             cwd=ROOT, capture_output=True, text=True, timeout=timeout)
    return process.returncode, process.stdout + process.stderr


@pytest.fixture(scope='module')
def rig_run(tmp_path_factory):
    bag = tmp_path_factory.mktemp('rig') / 'run'
    code, output = command('run', '--task', TASK, '--evaluators', 0, '--rig', 'sim',
                           '--bag', bag, '--domain-id', 'auto', *BUDGET)
    assert code == 0, output
    return bag


@pytest.fixture(scope='module')
def reevaluation(rig_run):
    out = rig_run.parent / 'reevaluated'
    code, output = command('evaluate', rig_run, '--rig', 'sim', '--rig-rate', 100,
                           '--rig-phase', 0.5, '--top', 2, '--out', out, '--domain-id', 'auto')
    assert code == 0, output
    return out, output


def test_a_run_scored_on_a_rig_every_physics_step_gives_the_simulated_objectives(rig_run):
    record = read_run(rig_run)
    task = run_task_of(record)
    evaluations = record.evaluations
    stages = 2 if task.two_stage else 1  # Task 1 runs without, then with randomization
    assert len(evaluations) == stages * task.iterations * task.population
    assert np.all(evaluations['measured']) and np.all(evaluations['status'] == 0)
    for row in range(len(evaluations)):
        design = recorded_design(record, int(evaluations['candidate_id'][row]))
        simulated = evaluate(design.x, design_task(record, design))  # its stage's worlds
        np.testing.assert_array_equal(design.objectives, simulated.objectives)
        np.testing.assert_array_equal(design.world_objectives, simulated.world_objectives)
        assert bool(evaluations['collision'][row]) == simulated.collision
    # the bag holds every trial's pose trace: a pose per physics step from 0 to its end
    traces = [trace for trace in trial_traces(rig_run) if trace.outcome == 'ended']
    assert traces
    for trace in traces:
        steps = int(round(trace.duration / task.time_step))
        np.testing.assert_allclose(trace.times, np.arange(steps + 1) * task.time_step,
                                   atol=1e-9)


def test_candidates_carry_the_design_in_physical_terms(rig_run):
    candidates = read_run(rig_run).candidates
    assert all(len(names) == len(values) > 0 for names, values in
               zip(candidates['design_names'], candidates['design_values']))
    assert all(urdf.startswith('<?xml') and '<capsule' not in urdf
               for urdf in candidates['hand_urdf'])
    assert set(candidates['controller_kind']) == {'pd'}


def test_best_designs_on_a_100_hz_rig_are_within_the_derived_tolerance(rig_run,
                                                                       reevaluation):
    out, output = reevaluation
    assert 'prediction (simulation) against measurement (rig), 2 designs' in output
    record = read_run(out)
    task = run_task_of(record)
    schedule = goal_schedule(task)
    comparison = rig_comparison(record)
    assert len(comparison.candidate_ids) == 2
    position = np.array([name.startswith('position') for name in comparison.objective_names])
    traces = trial_traces(out)
    for row, candidate_id in enumerate(comparison.candidate_ids.tolist()):
        x = recorded_design(read_run(rig_run), candidate_id).x
        np.testing.assert_array_equal(comparison.predicted[row], evaluate(x, task).objectives)
        # eq. 5 averages the worlds: its gap is at most the largest world's tolerance
        mine = [trace for trace in traces if trace.candidate_id == candidate_id]
        assert len(mine) == task.num_world_states
        tolerance = np.max([interpolation_tolerance(schedule, trace.times, trace.positions,
                                                    trace.orientations) for trace in mine],
                           axis=0)
        bound = np.where(position, tolerance[0], tolerance[1])
        assert np.all(np.abs(comparison.gap[row]) <= bound)
        assert bound.max() < 0.01   # a bound that says something: 1 cm, 0.01 rad
    assert np.abs(comparison.gap).max() > 0   # the poses were interpolated


def test_analyze_reports_the_gap(reevaluation, tmp_path):
    out, _ = reevaluation
    code, output = command('analyze', out, '--out', tmp_path / 'report')
    assert code == 0, output
    assert 'prediction (simulation) against measurement (rig)' in output
    text = (tmp_path / 'report' / 'report.md').read_text()
    assert '## Prediction and measurement' in text and 'rig_gap.png' in text
    lines = (tmp_path / 'report' / 'rig_gap.csv').read_text().splitlines()
    assert lines[0] == 'candidate_id,objective,predicted,measured,gap'
    assert len(lines) == 1 + 2 * len(run_task_of(read_run(out)).objective_names)


def test_evaluate_without_a_rig_is_one_clear_error(rig_run):
    code, output = command('evaluate', rig_run)
    assert code == 2
    assert output.strip() == ('hand-codesign evaluate: error: --rig: expected "hardware" (a '
                              'test rig joins the ROS domain) or "sim" (a simulated rig); '
                              'evaluating without a rig is `replay`')
