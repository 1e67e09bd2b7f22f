"""A real run on MuJoCo: `hand-codesign run --engine mujoco`, end to end, with two evaluators."""

import json
import pathlib

from analysis_run import run_cli
from hand_codesign.analysis.export import load_export
from hand_codesign.bag.reader import read_run
from hand_codesign.core.evaluate import evaluate
from hand_codesign.core.run.runs import engine_version
from hand_codesign.core.sim.geometry import link_frames
from hand_codesign.core.sim.hand import hand_model
import mujoco
import numpy as np
import pytest
from test_system import finish, run_killing_an_evaluator, start_run, summaries

pytestmark = pytest.mark.system

TASK = pathlib.Path(__file__).resolve().parents[3] / 'config' / 'tasks' / 'task5.yaml'
MUJOCO = ['--engine', 'mujoco']
# enough generations that an evaluator killed after the first still had work (a MuJoCo
# evaluation of 4 worlds takes about 15 ms)
GENERATIONS = 12
BUDGET = ['--iterations', str(GENERATIONS), '--population', '6', '--world-states', '4',
          '--seed', '7']


@pytest.fixture(scope='module')
def mujoco_run(tmp_path_factory):
    bag = tmp_path_factory.mktemp('mujoco') / 'bag'
    finish(start_run(bag, 2, extra=MUJOCO, budget=BUDGET, task=TASK))
    return bag


def test_a_run_on_mujoco_records_its_engine_and_evaluations_any_process_recomputes(
        mujoco_run, tmp_path):
    bag = mujoco_run
    record = read_run(bag)
    info = record.run_info
    assert (info.engine, info.engine_version) == ('mujoco', engine_version('mujoco'))
    task = info.task()
    assert task.physics.engine == 'mujoco'
    genomes = {}
    for index in range(len(record.candidates)):
        row = record.candidates.row(index)
        genomes[row['candidate_id']] = np.asarray(row['genome'], dtype=float)
    evaluators = set()
    for index in range(len(record.evaluations)):
        row = record.evaluations.row(index)
        evaluators.add(row['evaluator_id'])
        # answered by either evaluator process, recomputed here: the same bits
        again = evaluate(genomes[row['candidate_id']], task)
        np.testing.assert_array_equal(np.asarray(row['objectives']), again.objectives)
    assert len(evaluators) == 2
    # the final design's transfer: measured on unseen worlds in the other engine
    transfer = run_cli('analyze', bag, '--unseen', '2', '--engine', 'pybullet', '--out',
                       tmp_path / 'report')
    assert transfer.returncode == 0, transfer.stderr
    assert 'simulated with pybullet (the run used mujoco)' in transfer.stdout
    unseen = json.loads((tmp_path / 'report' / 'unseen.json').read_text())
    assert (unseen['engine'], unseen['run_engine']) == ('pybullet', 'mujoco')
    alone = run_cli('analyze', bag, '--engine', 'pybullet')
    assert alone.returncode == 2 and alone.stderr.strip().endswith('give --unseen N too')
    assert len(alone.stderr.strip().splitlines()) == 1
    # the design as MJCF: loads in MuJoCo and starts in the pose of the simulated hand
    exported = run_cli('export', bag, '--out', tmp_path / 'export')
    assert exported.returncode == 0, exported.stderr  # 0: re-simulated on MuJoCo, same bits
    model = mujoco.MjModel.from_xml_path(str(tmp_path / 'export' / 'hand.xml'))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key('initial').id)
    mujoco.mj_kinematics(model, data)
    design = load_export(tmp_path / 'export')
    hand = hand_model(design.design.hand, task.hand)
    base = (task.hand.base_position, task.hand.base_orientation)
    for link, (position, (x, y, z, w)) in zip(hand.links, link_frames(hand, base)):
        body = model.body(link.name).id
        np.testing.assert_allclose(data.xpos[body], position, atol=1e-7)  # MJCF: 9 digits
        assert abs(np.dot(data.xquat[body], (w, x, y, z))) == pytest.approx(1.0, abs=1e-7)


def test_a_killed_evaluator_changes_nothing_on_mujoco(mujoco_run, tmp_path):
    killed = tmp_path / 'killed'
    run_killing_an_evaluator(killed, BUDGET, extra=MUJOCO, after=f'generation 1/{GENERATIONS}')
    record = read_run(killed)
    assert record.run_info.engine == 'mujoco'
    ok = record.evaluations.select(record.evaluations['status'] == 0)
    assert sorted(set(ok['candidate_id'])) == list(range(GENERATIONS * 6))
    assert max(record.candidates['attempt']) >= 1, 'no candidate had to be sent again'
    assert summaries(killed) == summaries(mujoco_run)
