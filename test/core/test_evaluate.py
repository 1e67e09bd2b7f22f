"""evaluate(x, task): the contract's Evaluation, pure and bit-identical across processes."""

import hashlib
import json
import pathlib
import subprocess
import sys

from hand_codesign import ARITHMETIC
from hand_codesign.core import (evaluate, Evaluation, genome_spec, load_task, objective_names,
                                world_states)
from hand_codesign.core.task import parse_task, PhysicsSpec
import numpy as np
import pytest
import yaml

ROOT = pathlib.Path(__file__).resolve().parents[2]
TASKS = ROOT / 'config' / 'tasks'
PRESETS = sorted(path.name for path in TASKS.glob('*.yaml'))

# Evaluates genomes of Task 5 in the order given on the command line, after a Task 6
# candidate, and prints every float of the results exactly (hex).
SCRIPT = """
import json, sys
import numpy as np
from hand_codesign.core import evaluate, genome_spec, load_task
tasks = sys.argv[1]
task = load_task(tasks + '/task5.yaml').replace(num_world_states=3)
other = load_task(tasks + '/task6.yaml').replace(num_world_states=2)
evaluate(genome_spec(other).initial_mean() + 0.05, other)
genomes = json.loads(sys.argv[2])
results = {}
for index in json.loads(sys.argv[3]):
    result = evaluate(np.array(genomes[index]), task)
    values = np.concatenate([result.objectives, result.world_objectives.ravel(),
                             result.final_errors.ravel(), [result.fitness]])
    results[index] = [float(v).hex() for v in values]
print(json.dumps(results, sort_keys=True))
"""


@pytest.fixture(scope='module')
def task():
    return load_task(TASKS / 'task5.yaml').replace(num_world_states=3)


def genomes(task, count=4, seed=7):
    """Return seeded genomes around the mean, as CMA-ES draws them."""
    spec = genome_spec(task)
    generator = np.random.default_rng(seed)
    return [spec.initial_mean() + 0.1 * generator.standard_normal(spec.size)
            for _ in range(count)]


def exact(result):
    values = np.concatenate([result.objectives, result.world_objectives.ravel(),
                             result.final_errors.ravel(), [result.fitness]])
    return [float(v).hex() for v in values]


def test_evaluation_has_the_contract_fields(task):
    x = genomes(task)[0]
    result = evaluate(x, task)
    assert isinstance(result, Evaluation)
    names = objective_names(task)
    assert result.objective_names == tuple(names) == ('position_1', 'orientation_1')
    assert result.objectives.shape == (2,)
    assert result.world_objectives.shape == (3, 2)
    assert result.initial_errors.shape == result.final_errors.shape == (3, 2)
    assert result.fitness == pytest.approx(float(result.objectives @ task.objective_weights))
    assert not result.collision and result.unstable_worlds == 0
    assert result.simulated_time == pytest.approx(3 * 1.5)
    # eq. (5): the mean over the worlds plus the torque penalty
    penalty = result.objectives - result.world_objectives.mean(axis=0)
    assert penalty[0] == pytest.approx(penalty[1], abs=1e-12)
    torque = np.abs(genome_spec(task).decode(x).controller.values).max()
    spec = task.torque_penalty
    expected = spec.weight * (torque - spec.threshold) if torque > spec.threshold else 0.0
    assert penalty[0] == pytest.approx(expected, abs=1e-12)
    # the only goals are the last goals: their errors at the end are the world's objectives
    np.testing.assert_array_equal(result.final_errors, result.world_objectives)


def test_the_worst_worlds_score_a_real_evaluation_as_cvar(task):
    document = yaml.safe_load(task.source_text)
    document['worlds'] = {'aggregate': 'worst', 'fraction': 0.5}
    worst = parse_task(yaml.safe_dump(document), 'robust.yaml').replace(num_world_states=3)
    for x in genomes(task, count=2, seed=11):
        mean, cvar = evaluate(x, task), evaluate(x, worst)
        assert not mean.collision and mean.unstable_worlds == 0
        # the same worlds and rollouts, only combined otherwise
        np.testing.assert_array_equal(mean.world_objectives, cvar.world_objectives)
        penalty = mean.objectives - mean.world_objectives.mean(axis=0)
        # half of 3 worlds: the worst in full and the second worst at half weight, per
        # objective, plus the same torque penalty
        ordered = -np.sort(-cvar.world_objectives, axis=0)
        expected = (ordered[0] + 0.5 * ordered[1]) / 1.5 + penalty
        np.testing.assert_allclose(cvar.objectives, expected, rtol=1e-12, atol=1e-15)
        assert np.all(cvar.objectives >= mean.objectives)
        assert cvar.fitness == pytest.approx(float(cvar.objectives @ worst.objective_weights))


@pytest.mark.system
def test_bit_identical_in_other_processes_and_orders(task):
    candidates = genomes(task)
    assert not any(evaluate(x, task).collision for x in candidates)  # all of them simulated
    here = {str(index): exact(evaluate(x, task)) for index, x in enumerate(candidates)}
    payload = json.dumps([x.tolist() for x in candidates])
    for order in ([3, 2, 1, 0], [1, 3, 0, 2]):
        output = subprocess.run(
            [sys.executable, '-c', SCRIPT, str(TASKS), payload, json.dumps(order)],
            check=True, capture_output=True, text=True, timeout=120, cwd=ROOT).stdout
        assert json.loads(output.strip().splitlines()[-1]) == here
    # and in this process after other evaluations, in another order
    for index in (2, 0):
        assert exact(evaluate(candidates[index], task)) == here[str(index)]


def test_each_world_is_independent_of_the_others(task):
    x = genomes(task)[1]
    full = evaluate(x, task)
    worlds = world_states(task)
    for index in (2, 0):
        alone = evaluate(x, task, worlds=[worlds[index]])
        np.testing.assert_array_equal(alone.world_objectives[0], full.world_objectives[index])
        np.testing.assert_array_equal(alone.final_errors[0], full.final_errors[index])


# SHA-256 (first 20 hex digits) of the per-world objectives, final errors and simulated time
# of Task 5 candidates on 4 worlds, as evaluate() computed them before the physics settings
# became a task option (Task 5 with its plane and orientation goals, as config/reproduce/
# pins it): Table I's settings must keep them bit for bit. Change them only with a change that
# means to change the physics. The last bits depend on the kernels numpy dispatches to
# (hand_codesign.arithmetic): the first set is what processors with AVX-512 gave natively (the
# machines the tests ran on until 2026-12-03), the second what AVX2 processors give (an AMD EPYC
# with AVX2 and FMA and no AVX-512), and what every processor with AVX2 gives since the package
# pins numpy's dispatch to X86_V3. With GLIBC_TUNABLES=glibc.cpu.hwcaps=-FMA all four change.
NATIVE_AVX512_DIGESTS = {3: '0b679deb599651639627', 6: '03d599aa93b67155cb2c',
                         8: 'c1cb14611ae5202ca227', 9: '92fcb6db2a9632990f59'}
PINNED_DIGESTS = {3: '0b679deb599651639627', 6: '12e6c9e8e13cba0ccee1',
                  8: 'c1cb14611ae5202ca227', 9: '92fcb6db2a9632990f59'}


def digest(result):
    values = np.concatenate([result.world_objectives.ravel(), result.final_errors.ravel(),
                             [result.simulated_time]])
    return hashlib.sha256(values.tobytes()).hexdigest()[:20]


def test_table_one_physics_gives_the_earlier_results_bit_for_bit():
    task = load_task(TASKS.parent / 'reproduce' / 'task5.yaml').replace(num_world_states=4)
    spec = genome_spec(task)
    generator = np.random.default_rng(5)
    candidates = [spec.initial_mean() + 0.3 * generator.standard_normal(spec.size)
                  for _ in range(10)]
    found = {index: digest(evaluate(candidates[index], task)) for index in PINNED_DIGESTS}
    if ARITHMETIC.startswith('pinned'):
        assert found == PINNED_DIGESTS
    else:   # a processor without AVX2, or HAND_CODESIGN_NATIVE_ARITHMETIC=1
        assert found in (PINNED_DIGESTS, NATIVE_AVX512_DIGESTS)


def test_cheaper_physics_changes_results_and_stays_deterministic(task):
    cheap = task.replace(physics=PhysicsSpec(solver_iterations=5,
                                             contact_breaking_threshold=0.005))
    x = genomes(task)[2]
    first = exact(evaluate(x, cheap))
    table_one = exact(evaluate(x, task))  # Bullet's contact threshold is process-wide
    assert exact(evaluate(x, cheap)) == first
    assert first != table_one
    assert exact(evaluate(x, task)) == table_one


@pytest.mark.parametrize('name', PRESETS)
def test_every_preset_evaluates_a_candidate(name):
    task = load_task(TASKS / name).replace(num_world_states=2)
    spec = genome_spec(task)
    result = evaluate(spec.initial_mean(), task)
    assert result.objective_names == tuple(objective_names(task))
    assert result.objectives.shape == (len(result.objective_names),)
    assert np.isfinite(result.objectives).all() and np.isfinite(result.fitness)
    assert np.isfinite(result.final_errors).all()
    assert result.world_objectives.shape == (2, len(result.objective_names))
