"""
The hand the ROS way: the best design as robot_description and its rollout as /tf.

What RViz's RobotModel and Foxglove's URDF layer rely on, checked with readers independent of
the project (mcap-ros2-support and rosbags decode the messages from the schemas the files
hold, yourdfpy parses the URDF): the bag of a short real run (real nodes over DDS in separate
processes, test/analysis_run.py) holds the URDF that `export` writes, the palm fixed in the
world on /tf_static and on /tf, frame by frame, a transform for every joint of that URDF, from
its parent link to its child link, that moves; the last frames are the final best design's
whole rollout, as `core.experiments.motion` re-simulates it. `replay --mcap` writes the same.
The Foxglove layout is installed to share/ and reads the robot model.
"""

import contextlib
import itertools
import json
import random
import subprocess
import sys

from analysis_run import decoded_messages
from analysis_run import ROOT
from analysis_run import TASK
from hand_codesign.analysis import records
from hand_codesign.cli import main
from hand_codesign.core import contract
from hand_codesign.core.experiments.motion import rollout_motion
from hand_codesign.core.rotations import compose
from hand_codesign.core.run.runs import load_run_task
from hand_codesign.core.sim.geometry import joint_transforms
from hand_codesign.core.sim.geometry import link_frames
from hand_codesign.core.sim.hand import hand_model
from hand_codesign.core.sim.hand import PALM_LINK
from hand_codesign.core.sim.worlds import world_states
from hand_codesign.core.task.genome import genome_spec
from hand_codesign.ros import conversions
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
import numpy as np
import pytest
from rclpy.serialization import deserialize_message
from rclpy.serialization import serialize_message
from tf2_msgs.msg import TFMessage

LAYOUT = 'foxglove_layout.json'


def urdf_joints(text, tmp_path):
    """Return {child link: (joint name, parent link)} and the links of a URDF, by yourdfpy."""
    import yourdfpy
    path = tmp_path / 'parsed.urdf'
    path.write_text(text)
    robot = yourdfpy.URDF.load(str(path), build_scene_graph=False, load_meshes=False)
    return ({joint.child: (name, joint.parent) for name, joint in robot.joint_map.items()},
            set(robot.link_map))


def frames_of(messages):
    """Return {child frame: (parent frame, translation, quaternion xyzw)} of a TFMessage."""
    return {t.child_frame_id: (t.header.frame_id,
                               (t.transform.translation.x, t.transform.translation.y,
                                t.transform.translation.z),
                               (t.transform.rotation.x, t.transform.rotation.y,
                                t.transform.rotation.z, t.transform.rotation.w))
            for t in messages.transforms}


def link_poses_of(frames, palm):
    """Return {link: world pose} composed from the palm's pose down the transforms."""
    poses = {PALM_LINK: palm}
    while len(poses) <= len(frames):
        for child, (parent, translation, rotation) in frames.items():
            if parent in poses and child not in poses:
                poses[child] = compose(poses[parent], (translation, rotation))
    return poses


def best_motion(bag):
    """Return (task, physical design, RecordedDesign, Motion in world 0) of a bag's best."""
    record = records.open_run(bag)
    design = records.recorded_design(record, records.best_candidate_id(record))
    task = records.design_task(record, design)
    physical = genome_spec(task).decode(design.x)
    return task, physical, design, rollout_motion(physical, task, world_states(task)[0])


def test_joint_transforms_compose_to_the_simulated_link_frames():
    task = load_run_task(TASK, world_states=2)
    spec = genome_spec(task)
    design = spec.decode(np.linspace(0.2, 0.8, spec.size))
    motion = rollout_motion(design, task, world_states(task)[0])
    assert motion.simulated and len(motion.times) > 10
    assert np.allclose(np.diff(motion.times), 0.04)                  # 25 frames per second
    model = hand_model(design.hand, task.hand)
    for angles, links in zip(motion.joint_angles, motion.link_poses):
        frames = {child: (parent, *pose) for parent, child, pose in
                  joint_transforms(model, angles)}
        composed = link_poses_of(frames, motion.palm)
        for link, (position, orientation) in zip(model.links, links):
            # PyBullet reports link frames in single precision
            assert np.allclose(composed[link.name][0], position, atol=1e-6)
            assert min(np.max(np.abs(np.subtract(composed[link.name][1], orientation))),
                       np.max(np.abs(np.add(composed[link.name][1], orientation)))) < 1e-6
    # at the initial angles they are forward kinematics of the design as built
    composed = link_poses_of({c: (p, *pose) for p, c, pose in joint_transforms(model)},
                             motion.palm)
    for link, (position, _) in zip(model.links, link_frames(model, motion.palm)):
        assert np.allclose(composed[link.name][0], position, atol=1e-12)


def test_tf_message_round_trips_through_rclpy():
    from builtin_interfaces.msg import Time
    transforms = [('palm', 'finger0_segment0', ((0.01, 0.02, 0.03), (0.0, 0.0, 0.6, 0.8)))]
    message = conversions.tf_message(transforms, Time(sec=5, nanosec=7))
    back = deserialize_message(serialize_message(message), TFMessage)
    assert frames_of(back) == {'finger0_segment0': ('palm', (0.01, 0.02, 0.03),
                                                    (0.0, 0.0, 0.6, 0.8))}
    assert (back.transforms[0].header.stamp.sec, back.transforms[0].header.stamp.nanosec) == (
        5, 7)


@pytest.mark.system
def test_the_bag_holds_the_best_design_as_a_robot_model_that_moves(real_run, tmp_path):
    descriptions = decoded_messages(real_run.mcap, contract.ROBOT_DESCRIPTION)
    statics = decoded_messages(real_run.mcap, contract.TF_STATIC)
    moving = decoded_messages(real_run.mcap, contract.TF)
    assert descriptions and len(statics) == len(descriptions) and moving
    task, physical, design, motion = best_motion(real_run.bag)
    # the last description is the final best design, the very text `export` writes
    assert main(['export', str(real_run.bag), '--out', str(tmp_path / 'export')]) == 0
    assert descriptions[-1].data == (tmp_path / 'export' / 'hand.urdf').read_text()
    joints, links = urdf_joints(descriptions[-1].data, tmp_path)
    model = hand_model(physical.hand, task.hand)
    assert links == {PALM_LINK} | {link.name for link in model.links}
    assert {name for name, _ in joints.values()} == {link.joint_name for link in model.links}
    # the palm is fixed in the world where the task mounts it
    (parent, translation, rotation), = [frames_of(statics[-1])[PALM_LINK]]
    assert parent == contract.WORLD_FRAME
    assert np.allclose(translation, task.hand.base_position)
    assert np.allclose(rotation, task.hand.base_orientation)
    # every /tf message: one transform per joint of the URDF, parent link to child link
    for message in moving:
        frames = frames_of(message)
        assert set(frames) <= set(joints)
        assert all(parent == joints[child][1] for child, (parent, *_) in frames.items())
    last = [frames_of(message) for message in moving[-len(motion.times):]]
    assert all(set(frames) == set(joints) for frames in last)
    # ... and the last ones are the final best design's whole rollout in world 0, moving
    for frames, angles in zip(last, motion.joint_angles):
        for parent, child, (position, orientation) in joint_transforms(model, angles):
            assert frames[child][0] == parent
            assert np.allclose(frames[child][1], position, atol=1e-12)
            assert np.allclose(frames[child][2], orientation, atol=1e-12)
    assert min(abs(np.dot(last[0][c][2], last[-1][c][2])) for c in last[0]) < 1 - 1e-6


@pytest.mark.system
def test_the_bag_reads_as_tf_with_rosbags(real_run):
    from rosbags.highlevel import AnyReader
    with AnyReader([real_run.bag]) as bag:
        connections = [c for c in bag.connections
                       if c.topic in ('/' + contract.TF, '/' + contract.TF_STATIC,
                                      '/' + contract.ROBOT_DESCRIPTION)]
        assert {c.msgtype for c in connections} == {contract.TF_MESSAGE_TYPE,
                                                    contract.STRING_TYPE}
        decoded = [bag.deserialize(raw, c.msgtype) for c, _, raw in bag.messages(connections)]
    transforms = [t for m in decoded if hasattr(m, 'transforms') for t in m.transforms]
    assert transforms and all(t.header.frame_id and t.child_frame_id for t in transforms)
    assert any(m.data.startswith('<?xml') for m in decoded if hasattr(m, 'data'))


@pytest.mark.system
def test_replay_mcap_holds_the_robot_model_and_its_motion(real_run, tmp_path):
    out = tmp_path / 'rollout.mcap'
    assert main(['replay', str(real_run.bag), '--mcap', str(out)]) == 0
    by_topic = {}
    with open(out, 'rb') as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        for _, channel, message, decoded in reader.iter_decoded_messages():
            by_topic.setdefault(channel.topic.lstrip('/'), []).append(
                (message.log_time, decoded))
    task, physical, design, motion = best_motion(real_run.bag)
    assert main(['export', str(real_run.bag), '--out', str(tmp_path / 'export')]) == 0
    (time, description), = by_topic[contract.ROBOT_DESCRIPTION]
    assert time == 0 and description.data == (tmp_path / 'export' / 'hand.urdf').read_text()
    (time, static), = by_topic[contract.TF_STATIC]
    assert time == 0 and frames_of(static)[PALM_LINK][0] == contract.WORLD_FRAME
    moving = by_topic[contract.TF]
    markers = by_topic[contract.REPLAY_MARKERS]
    assert [t for t, _ in moving] == [t for t, _ in markers]         # one per drawn frame
    assert len(moving) == len(motion.times)
    joints, _ = urdf_joints(description.data, tmp_path)
    model = hand_model(physical.hand, task.hand)
    for (_, message), angles in zip(moving, motion.joint_angles):
        frames = frames_of(message)
        assert set(frames) == set(joints)
        for parent, child, (position, orientation) in joint_transforms(model, angles):
            assert frames[child][0] == parent
            assert np.allclose(frames[child][2], orientation, atol=1e-12)
    first, last = frames_of(moving[0][1]), frames_of(moving[-1][1])
    assert min(abs(np.dot(first[c][2], last[c][2])) for c in first) < 1 - 1e-6


@pytest.fixture(scope='module')
def installed_share(tmp_path_factory):
    """Return share/hand_codesign as setup.py installs its data files (install_data)."""
    base = tmp_path_factory.mktemp('installed')
    result = subprocess.run([sys.executable, 'setup.py', '-q', 'install_data', '--install-dir',
                             str(base)], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    return base / 'share' / 'hand_codesign'


@pytest.mark.system
def test_the_layout_is_installed_and_shows_the_robot_model(installed_share):
    installed = installed_share / 'config' / LAYOUT
    assert installed.read_bytes() == (ROOT / 'config' / LAYOUT).read_bytes()
    assert (installed_share / 'config' / 'robot_view.yaml').is_file()
    layout = json.loads(installed.read_text())
    urdf_layers = [layer for panel, config in layout['configById'].items()
                   if panel.startswith('3D!') for layer in config.get('layers', {}).values()
                   if layer.get('layerId') == 'foxglove.Urdf']
    assert [(layer['sourceType'], layer['topic']) for layer in urdf_layers] == [
        ('topic', '/' + contract.ROBOT_DESCRIPTION)]
    # every evaluator's status is read, however many there are: no panel names an evaluator
    text = json.dumps(layout)
    assert 'evaluator_id' not in text and 'evaluator-' not in text
    assert '/' + contract.EVALUATOR_STATUS + '.' in text


def test_the_robot_view_is_a_console_script_with_a_parameter_file():
    import importlib.metadata
    scripts = {entry.name: entry.value for entry in
               importlib.metadata.distribution('hand_codesign').entry_points}
    assert scripts['robot_view'] == 'hand_codesign.ros.robot_view_node:main'
    from hand_codesign.ros.robot_view_node import PARAMETERS
    import yaml
    given = yaml.safe_load((ROOT / 'config' / 'robot_view.yaml').read_text())
    assert given['/**']['ros__parameters'] == {
        name: default for name, (default, _, _) in PARAMETERS.items()}


PROBE = """
import json
import sys
import time

from hand_codesign.core import contract
from hand_codesign.ros import topics
from mcap.reader import make_reader
import rclpy
from rclpy.node import Node
from rclpy.serialization import deserialize_message
from std_msgs.msg import String
from tf2_msgs.msg import TFMessage

raw = {}
with open(sys.argv[1], 'rb') as stream:
    for _, channel, message in make_reader(stream).iter_messages():
        raw.setdefault(channel.topic.lstrip('/'), []).append(message.data)
sent = {name: deserialize_message(raw[name][index], topics.MESSAGE_TYPES[name]) for name, index
        in ((contract.RUN_INFO, 0), (contract.GENERATION_SUMMARY, -1))}
rclpy.init()
node = Node('robot_view_probe')
got = {contract.TF: [], contract.TF_STATIC: [], contract.ROBOT_DESCRIPTION: []}


def frames(message):
    return {t.child_frame_id: [t.header.frame_id, [t.transform.rotation.x, t.transform.rotation.y,
                                                   t.transform.rotation.z, t.transform.rotation.w]]
            for t in message.transforms}


node.create_subscription(TFMessage, contract.TF, lambda m: got[contract.TF].append(frames(m)),
                         topics.TF_QOS)
publishers = {name: node.create_publisher(type(message), name, topics.QOS[name])
              for name, message in sent.items()}


def spin_until(done, timeout):
    deadline = time.monotonic() + timeout
    while not done() and time.monotonic() < deadline:
        rclpy.spin_once(node, timeout_sec=0.05)
    return done()


if not spin_until(lambda: all(p.get_subscription_count() for p in publishers.values()), 60):
    sys.exit('the robot view never subscribed')
for name, message in sent.items():
    publishers[name].publish(message)
if not spin_until(lambda: got[contract.TF], 60):
    sys.exit('no /tf came')
# a late subscriber still gets the description and the palm: transient local
node.create_subscription(String, contract.ROBOT_DESCRIPTION,
                         lambda m: got[contract.ROBOT_DESCRIPTION].append(m.data),
                         topics.LATCHED_QOS)
node.create_subscription(TFMessage, contract.TF_STATIC,
                         lambda m: got[contract.TF_STATIC].append(frames(m)), topics.LATCHED_QOS)
spin_until(lambda: False, float(sys.argv[2]))
print(json.dumps(got))
node.destroy_node()
rclpy.shutdown()
"""


@pytest.mark.system
def test_the_robot_view_node_serves_a_late_viewer_and_ends_after_the_final_design(
        real_run, tmp_path):
    import domain_coordinator
    from bag_samples import ros_env
    task, physical, design, motion = best_motion(real_run.bag)
    duration = len(motion.times) / 25
    # a domain of 200 to 232 (as test_recorder's): runs of `--domain-id auto` take 1 to 100
    first = random.randrange(200, 233)
    domains = itertools.cycle([*range(first, 233), *range(200, first)])
    with domain_coordinator.domain_id(selector=lambda: next(domains)) as domain:
        env = ros_env(domain)
        view = subprocess.Popen([sys.executable, '-m', 'hand_codesign.ros.robot_view_node'],
                                env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                text=True)
        try:
            probe = subprocess.run([sys.executable, '-c', PROBE, str(real_run.mcap),
                                    str(duration + 3.0)], env=env, capture_output=True,
                                   text=True, timeout=180)
            with contextlib.suppress(subprocess.TimeoutExpired):
                view.wait(timeout=30)     # it ends once the final design has played
        finally:
            if view.poll() is None:
                view.kill()
            output = view.communicate()[0]
    assert probe.returncode == 0, probe.stderr + output
    assert view.returncode == 0, output
    got = json.loads(probe.stdout)
    urdf = decoded_messages(real_run.mcap, contract.ROBOT_DESCRIPTION)[-1].data
    assert got[contract.ROBOT_DESCRIPTION] == [urdf]
    assert got[contract.TF_STATIC][-1][PALM_LINK][0] == contract.WORLD_FRAME
    played = got[contract.TF]
    assert len(motion.times) // 2 <= len(played) <= len(motion.times)
    model = hand_model(physical.hand, task.hand)
    for frames, angles in zip(played[::-1], motion.joint_angles[::-1]):   # from the last on
        for parent, child, (_, orientation) in joint_transforms(model, angles):
            assert frames[child][0] == parent
            assert np.allclose(frames[child][1], orientation, atol=1e-12)


def test_the_launch_ends_once_the_final_design_has_played(monkeypatch):
    import importlib.util
    import types
    # ROS's launch packages are not on PyPI: stand-ins keep what they are given (test_launch)
    for name, classes in {'launch': ['LaunchDescription'],
                          'launch.actions': ['DeclareLaunchArgument', 'EmitEvent',
                                             'OpaqueFunction', 'RegisterEventHandler',
                                             'TimerAction'],
                          'launch.event_handlers': ['OnProcessExit'],
                          'launch.events': ['Shutdown'], 'launch_ros': [],
                          'launch_ros.actions': ['Node']}.items():
        module = types.ModuleType(name)
        for class_name in classes:
            setattr(module, class_name, type(class_name, (), {
                '__init__': lambda self, *a, **k: setattr(self, 'keywords', k)}))
        monkeypatch.setitem(sys.modules, name, module)
    spec = importlib.util.spec_from_file_location('codesign_launch',
                                                  ROOT / 'launch' / 'codesign.launch.py')
    launch = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(launch)

    def kinds(actions):
        return [type(action).__name__ for action in actions]

    ended = types.SimpleNamespace
    assert kinds(launch.after_run(ended(returncode=1), None)) == ['EmitEvent']   # failed: now
    waiting, = launch.after_run(ended(returncode=0), None)
    assert type(waiting).__name__ == 'TimerAction'
    assert waiting.keywords['period'] == launch.ROBOT_VIEW_WAIT
    assert kinds(waiting.keywords['actions']) == ['EmitEvent']
    assert kinds(launch.after_view(ended(returncode=0), None)) == ['EmitEvent']
    assert launch.after_view(ended(returncode=2), None) == []   # a failed view ends nothing
