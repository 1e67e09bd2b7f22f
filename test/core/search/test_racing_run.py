"""A raced run as a user runs it: real processes over DDS, the same with 1 or 2 evaluators."""

import json
import pathlib
import subprocess
import sys

from hand_codesign.analysis.records import (best_candidate_id, evaluation_rows, open_run,
                                            recorded_design, stepping_rate, told_objectives,
                                            told_worlds)
from hand_codesign.analysis.resume import resume_point
from hand_codesign.bag.reader import read_run
import numpy as np
import pytest
import yaml

pytestmark = pytest.mark.system

ROOT = pathlib.Path(__file__).resolve().parents[3]
BUDGET = ['--iterations', '2', '--population', '8', '--world-states', '4', '--seed', '7']
# a band this narrow (10 micrometres) is no sensible statement about Task 5's worlds: it only
# makes the race stop candidates of a run this small, whose designs score within 0.1 mm
RACING = {'rounds': 2, 'range': 0.00001}
FIELDS = ['told_ids', 'told_objectives', 'told_worlds', 'best_candidate_id', 'best_fitness']


def raced_task(folder):
    document = yaml.safe_load((ROOT / 'config' / 'tasks' / 'task5.yaml').read_text())
    document['worlds'] = {'racing': RACING}
    path = folder / 'raced.yaml'
    path.write_text(yaml.safe_dump(document))
    return path


def run(task, bag, evaluators):
    command = [sys.executable, '-m', 'hand_codesign.cli', 'run', '--task', str(task),
               '--evaluators', str(evaluators), '--bag', str(bag), '--domain-id', 'auto',
               *BUDGET]
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    run_id = json.loads((bag / 'result.json').read_text())['run_id']
    table = read_run(bag, run_id=run_id).generation_summaries
    return [{name: np.asarray(table[name][row]).tolist() for name in FIELDS}
            for row in range(len(table))]


def test_a_raced_run_is_the_same_with_one_and_two_evaluators(tmp_path):
    task = raced_task(tmp_path)
    one = run(task, tmp_path / 'one', 1)
    two = run(task, tmp_path / 'two', 2)
    assert repr(one) == repr(two)   # (the final summary's empty lists read back as NaN)
    worlds = [count for summary in one[:-1] for count in summary['told_worlds']]
    assert len(worlds) == 16 and max(worlds) == 4
    assert min(worlds) == 2, 'no candidate was stopped after its first round'
    # the rounds travel as further attempts with their share of the worlds
    candidates = read_run(tmp_path / 'two').candidates
    assert {(int(a), int(b)) for a, b in zip(candidates['worlds_from'],
                                             candidates['worlds_to'])} == {(0, 2), (2, 4)}
    # what a resume reads back: stopped candidates as such
    record = open_run(tmp_path / 'one')
    assert sorted({count for count, _ in told_worlds(record).values()}) == [2, 4]
    # the analysis reads the rounds as parts of the told evaluations
    statuses = set(evaluation_rows(record).status.tolist())
    assert 'round' in statuses and 'untold' not in statuses and stepping_rate(record) > 0
    best = best_candidate_id(record)
    design = recorded_design(record, best)
    assert design.objectives.tobytes() == told_objectives(record)[best].tobytes()
    assert design.world_objectives.shape == (4, 2)
    point = resume_point(record, iterations=3)
    assert point.evaluations_told == 16 and not point.known
    # what `analyze` tells a user: the rollouts the race ran and saved
    analyzed = subprocess.run([sys.executable, '-m', 'hand_codesign.cli', 'analyze',
                               str(tmp_path / 'one'), '--out', str(tmp_path / 'report')],
                              cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert analyzed.returncode == 0, analyzed.stderr
    stopped = sum(1 for count in worlds if count < 4)
    assert (f'{int(sum(worlds))} of 64 rollouts run ({stopped} of 16 candidates stopped early: '
            f'{1 - sum(worlds) / 64:.1%} of the rollouts saved)'
            in (tmp_path / 'report' / 'report.md').read_text())
