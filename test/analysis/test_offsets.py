"""`hand-codesign offsets`: where a run's best design leaves the object, axis by axis."""

import csv
import re
import subprocess
import sys

from analysis_run import BUDGET
from hand_codesign.analysis.records import final_design
from hand_codesign.core.experiments.measures import (measure_worlds, summarize, Tolerance,
                                                     unseen_world_states)
from hand_codesign.core.experiments.robustness import start_and_goal_poses
from hand_codesign.core.sim.worlds import world_states
import numpy as np
import pytest

pytestmark = pytest.mark.system

COMMAND = [sys.executable, '-m', 'hand_codesign.cli', 'offsets']


def test_shares_along_each_axis_are_the_measures_of_reproduce(real_run):
    completed = subprocess.run([*COMMAND, str(real_run.bag), '--unseen', '30'],
                               capture_output=True, text=True, timeout=300)
    assert completed.returncode == 0, completed.stderr
    task, x, _ = final_design(real_run.bag)
    worlds = unseen_world_states(task, 30)
    measures = measure_worlds(x, task, worlds)
    printed = dict(re.findall(r'along (\w): within 5 mm ([\d.]+) %', completed.stdout))
    for axis in 'xy':
        share = summarize(measures, Tolerance(axis, 0.005)).within
        assert float(printed[axis]) == round(100 * share, 1)
    # the final positions the slopes are fitted to are those the errors are measured from
    _, goals = start_and_goal_poses(task, worlds)
    np.testing.assert_allclose(
        np.linalg.norm(measures.final_positions[:, :2] - goals[:, :2], axis=1),
        measures.errors['plane'], rtol=0, atol=1e-12)


def test_training_worlds_are_the_runs_own_and_the_table_holds_both_sets(real_run, tmp_path):
    out = tmp_path / 'offsets'
    completed = subprocess.run(
        [*COMMAND, str(real_run.bag), '--unseen', '10', '--training',
         '--table', str(out)], capture_output=True, text=True, timeout=300)
    assert completed.returncode == 0, completed.stderr
    with out.with_suffix('.csv').open() as stream:
        rows = list(csv.DictReader(stream))
    trained = BUDGET[BUDGET.index('--world-states') + 1]
    assert [(row['worlds'], row['count']) for row in rows] == [
        ('training', trained), ('unseen', '10')]
    task, x, _ = final_design(real_run.bag)
    measures = measure_worlds(x, task, world_states(task))
    for axis in ('plane', 'x', 'y'):
        share = summarize(measures, Tolerance(axis, 0.005)).within
        assert float(rows[0][f'within_{axis}']) == share
    assert f'| training, {trained} |' in out.with_suffix('.md').read_text()


def test_a_path_that_is_not_a_bag_gets_one_line(tmp_path):
    completed = subprocess.run([*COMMAND, str(tmp_path)], capture_output=True,
                               text=True, timeout=300)
    assert completed.returncode == 2 and completed.stdout == ''
    lines = completed.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f'hand-codesign offsets: error: {tmp_path}: ')
