"""Task 5's PD variant: Table I's PD cells on Task 5, evaluated bit-identically anywhere."""

import dataclasses
import json
import math
import pathlib
import subprocess
import sys

from hand_codesign.core import evaluate, genome_spec, load_task
import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]
TASKS = ROOT / 'config' / 'tasks'

# Evaluates the genomes given on the command line in the order given; prints exact floats.
SCRIPT = """
import json, sys
import numpy as np
from hand_codesign.core import evaluate, load_task
task = load_task(sys.argv[1]).replace(num_world_states=3)
genomes = json.loads(sys.argv[2])
results = {}
for index in json.loads(sys.argv[3]):
    result = evaluate(np.array(genomes[index]), task)
    results[index] = [float(v).hex() for v in np.concatenate(
        [result.world_objectives.ravel(), result.final_errors.ravel(), [result.fitness]])]
print(json.dumps(results, sort_keys=True))
"""


@pytest.fixture(scope='module')
def task():
    return load_task(TASKS / 'task5_pd.yaml')


def test_table_one_pd_cells(task):
    policy = task.policy
    assert policy.kind == 'pd' and policy.gravity_compensation
    assert len(policy.keyframe_times) == 3 and policy.keyframe_times[-1] == task.duration
    for name, bounds in (('target', (-math.pi / 2, math.pi / 2)), ('kp', (1.0, 100.0)),
                         ('kd', (0.1, 10.0))):
        setting = getattr(policy, name)
        assert setting.mode == 'bounds'
        assert (setting.values[0].lower, setting.values[0].upper) == pytest.approx(bounds)
    spec = genome_spec(task)
    assert len(spec.indices('controller.target.')) == 3 * 4
    assert len(spec.indices('controller.kp.')) == len(spec.indices('controller.kd.')) == 4
    assert task.torque_penalty is None  # no torque parameters to penalize (eq. 2)


def test_everything_but_the_controller_is_task5s(task):
    task5 = load_task(TASKS / 'task5.yaml')
    own = {'name', 'description', 'policy', 'torque_penalty', 'source', 'source_text'}
    for field in dataclasses.fields(task5):
        if field.name not in own:
            assert getattr(task, field.name) == getattr(task5, field.name), field.name
    names, names5 = genome_spec(task).names, genome_spec(task5).names
    morphology = [name for name in names if not name.startswith('controller.')]
    assert morphology == [name for name in names5 if not name.startswith('controller.')]


@pytest.mark.system
def test_pd_evaluations_are_bit_identical_in_other_processes(task):
    spec = genome_spec(task)
    generator = np.random.default_rng(11)
    candidates = [spec.initial_mean() + 0.1 * generator.standard_normal(spec.size)
                  for _ in range(3)]
    small = task.replace(num_world_states=3)
    results = [evaluate(x, small) for x in candidates]
    assert not any(result.collision for result in results)  # all of them simulated
    assert not any(result.unstable_worlds for result in results)
    here = {str(index): [float(v).hex() for v in np.concatenate(
        [result.world_objectives.ravel(), result.final_errors.ravel(), [result.fitness]])]
        for index, result in enumerate(results)}
    output = subprocess.run(
        [sys.executable, '-c', SCRIPT, str(TASKS / 'task5_pd.yaml'),
         json.dumps([x.tolist() for x in candidates]), json.dumps([2, 0, 1])],
        check=True, capture_output=True, text=True, timeout=120, cwd=ROOT).stdout
    assert json.loads(output.strip().splitlines()[-1]) == here
