"""`hand-codesign export`: URDF and controller YAML of the best design, and their round trip."""

import math

from hand_codesign.analysis.export import load_export
from hand_codesign.analysis.export import resimulate
from hand_codesign.analysis.records import recorded_design
from hand_codesign.bag.reader import read_run
from hand_codesign.cli import main
from hand_codesign.core.sim.hand import build_hand
from hand_codesign.core.sim.hand import hand_model
from hand_codesign.core.task.genome import genome_spec
from hand_codesign.errors import UserError
import numpy as np
import pybullet
from pybullet_utils.bullet_client import BulletClient
import pytest
import yaml
import yourdfpy

pytestmark = pytest.mark.system


@pytest.fixture(scope='module')
def exported(real_run, tmp_path_factory):
    out = tmp_path_factory.mktemp('export') / 'best'
    assert main(['export', str(real_run.bag), '--out', str(out)]) == 0
    return out


def test_export_writes_urdf_and_yaml(exported, real_run, capsys):
    assert (exported / 'hand.urdf').exists() and (exported / 'controller.yaml').exists()
    document = yaml.safe_load((exported / 'controller.yaml').read_text())
    assert document['source']['candidate_id'] == real_run.result['best_candidate_id']
    assert document['task']['seed'] == 3 and document['task']['world_states'] == 2
    controller = document['controller']
    assert controller['kind'] == 'torque' and controller['mode'] == 'constant'
    assert controller['joints'] == ['finger0_segment0_joint', 'finger0_segment1_joint',
                                    'finger1_segment0_joint', 'finger1_segment1_joint']
    # the torques in N m are the optimizer's reported design, gene by gene
    design = real_run.result['design']
    assert controller['torques']['finger1_segment0_joint'] == [
        design['controller.torque.k0.finger1.joint0'],
        design['controller.torque.k1.finger1.joint0']]


def test_round_trip_gives_the_recorded_objectives(exported, real_run):
    export = load_export(exported)
    task = export.task
    best = recorded_design(read_run(real_run.bag), real_run.result['best_candidate_id'])
    assert export.design.hand == genome_spec(task).decode(best.x).hand
    recorded = np.array(list(real_run.result['objectives'].values()))
    assert np.array_equal(export.objectives, recorded)
    assert np.array_equal(resimulate(export).objectives, recorded)


def test_urdf_loads_in_yourdfpy_with_limits_axes_and_friction(exported):
    export = load_export(exported)
    model = hand_model(export.design.hand, export.task.hand)
    urdf = yourdfpy.URDF.load(str(exported / 'hand.urdf'), build_scene_graph=True,
                              load_meshes=False)
    joints = {joint.name: joint for joint in urdf.robot.joints}
    assert list(joints) == [link.joint_name for link in model.links]
    for link in model.links:
        joint = joints[link.joint_name]
        assert joint.type == 'revolute'
        assert np.allclose(joint.axis, link.joint_axis, atol=1e-15)
        assert (joint.limit.lower, joint.limit.upper) == (link.lower_limit, link.upper_limit)
        assert np.allclose(joint.origin[:3, 3], link.joint_position, atol=1e-15)
    text = (exported / 'hand.urdf').read_text()
    assert f'<lateral_friction value="{export.design.hand.friction!r}"' in text
    assert '<capsule' not in text


def test_urdf_in_pybullet_is_the_simulated_hand(exported):
    export = load_export(exported)
    model = hand_model(export.design.hand, export.task.hand)
    client = BulletClient(connection_mode=pybullet.DIRECT)
    try:
        loaded = client.loadURDF(
            str(exported / 'hand.urdf'), useFixedBase=True,
            flags=client.URDF_USE_SELF_COLLISION | client.URDF_USE_IMPLICIT_CYLINDER)
        built = build_hand(client, model)
        assert client.getNumJoints(loaded) == client.getNumJoints(built) == len(model.links)
        for index, link in enumerate(model.links):
            client.resetJointState(loaded, index, link.initial_angle)
            info = client.getJointInfo(loaded, index)
            assert info[1].decode() == link.joint_name
            assert (info[8], info[9]) == (link.lower_limit, link.upper_limit)
            dynamics = client.getDynamicsInfo(loaded, index)
            assert dynamics[0] == pytest.approx(link.mass, rel=1e-12)
            assert dynamics[1] == export.design.hand.friction
        for index in range(len(model.links)):
            frame_loaded = client.getLinkState(loaded, index, computeForwardKinematics=True)[4]
            frame_built = client.getLinkState(built, index, computeForwardKinematics=True)[4]
            assert np.allclose(frame_loaded, frame_built, atol=1e-9)
        # each capsule is a cylinder and two end spheres covering the very same volume
        shapes = client.getCollisionShapeData(loaded, 1)
        link = model.links[1]
        cylinder = [shape for shape in shapes if shape[2] == client.GEOM_CYLINDER]
        spheres = sorted((shape for shape in shapes if shape[2] == client.GEOM_SPHERE),
                         key=lambda shape: shape[5][1])
        assert len(cylinder) == 1 and len(spheres) == 2
        assert cylinder[0][3][:2] == pytest.approx((link.cylinder_height, link.radius))
        assert [sphere[3][0] for sphere in spheres] == [link.radius, link.radius]
        offsets = [sphere[5][1] for sphere in spheres]   # from the centre of mass, along y
        assert offsets == pytest.approx([-link.cylinder_height / 2, link.cylinder_height / 2])
    finally:
        client.disconnect()


def test_any_recorded_candidate_exports_and_an_unknown_one_is_one_line(real_run, tmp_path,
                                                                       capsys):
    # another elite of an archive, or any design of the run: here the first one evaluated
    record = read_run(real_run.bag)
    other = min(int(i) for i in record.evaluations['candidate_id'])
    assert other != real_run.result['best_candidate_id']
    out = tmp_path / 'other'
    assert main(['export', str(real_run.bag), '--out', str(out), '--candidate', str(other)]) == 0
    export = load_export(out)
    assert export.document['source']['candidate_id'] == other
    recorded = recorded_design(record, other)
    assert np.array_equal(export.objectives, recorded.objectives)
    assert np.array_equal(resimulate(export).objectives, recorded.objectives)
    capsys.readouterr()
    for wrong, message in (('999999', 'candidate 999999 is not in the bag'),
                           ('-1', '--candidate -1: expected a candidate id')):
        assert main(['export', str(real_run.bag), '--out', str(tmp_path / 'x'),
                     '--candidate', wrong]) == 2
        error = capsys.readouterr().err
        assert message in error and len(error.strip().splitlines()) == 1
    assert not (tmp_path / 'x').exists()


def test_broken_export_names_file_and_key(exported, tmp_path):
    text = (exported / 'controller.yaml').read_text()
    broken = tmp_path / 'controller.yaml'
    broken.write_text(text.replace('segment_lengths:', 'segment_length:', 1))
    with pytest.raises(UserError, match=r'controller.yaml: design.fingers\[0\]'
                                        r'.segment_length: expected no such key'):
        load_export(tmp_path)
    broken.write_text('format: something else\n')
    with pytest.raises(UserError, match='format: expected'):
        load_export(tmp_path)


def test_initial_angles_are_in_the_yaml(exported):
    export = load_export(exported)
    angles = export.document['controller']['initial_angles']
    model = hand_model(export.design.hand, export.task.hand)
    assert [angles[link.joint_name] for link in model.links] == list(model.initial_angles)
    assert all(math.isfinite(angle) for angle in angles.values())
