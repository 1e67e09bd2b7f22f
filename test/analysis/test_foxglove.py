"""
A run seen in 3D: its bag's markers, a replayed rollout as a ROS 2 MCAP, the layout, live view.

What a person opening Foxglove relies on: the bag holds the best design of each generation as
visualization_msgs/MarkerArray drawn from the core's hand model; `replay --mcap` writes a
standard ROS 2 MCAP (read here by mcap-ros2-support and rosbags, which parse the schemas
themselves) whose first frame is the design as built and whose frames advance in time; the
layout names only topics and fields that exist; `run --live` serves the run's messages on
the loopback interface, byte for byte as the bag records them.
"""

import asyncio
import json
import os
import queue
import re
import socket
import struct
import subprocess
import sys
import threading

from analysis_run import CLI
from analysis_run import decoded_messages
from analysis_run import raw_messages
from analysis_run import ROOT
from analysis_run import TASK
from hand_codesign.analysis import records
from hand_codesign.cli import main
from hand_codesign.core import contract
from hand_codesign.core.sim.geometry import design_shapes
from hand_codesign.core.sim.geometry import goal_poses
from hand_codesign.core.sim.worlds import object_state
from hand_codesign.core.sim.worlds import world_states
from hand_codesign.core.task.genome import genome_spec
from hand_codesign.ros import topics
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
import numpy as np
import psutil
import pytest

LAYOUT = ROOT / 'config' / 'foxglove_layout.json'
MCAP_MAGIC = b'\x89MCAP0\r\n'
DRAWN = ('palm', 'segments', 'joint_axes')
# the Foxglove WebSocket protocol: foxglove-sdk's name for it, and the older one
SUBPROTOCOLS = ['foxglove.sdk.v1', 'foxglove.websocket.v1']
LIVE_BUDGET = ['--iterations', '3', '--population', '4', '--world-states', '1', '--seed', '3']


def marker_positions(markers, groups=DRAWN):
    """Return {(ns, id): (type, position, scale)} of decoded markers in some groups."""
    return {(m.ns, m.id): (m.type, (m.pose.position.x, m.pose.position.y, m.pose.position.z),
                           (m.scale.x, m.scale.y, m.scale.z))
            for m in markers if m.ns in groups}


def shape_positions(shapes, groups=DRAWN):
    """Return the same mapping for core.sim.geometry Shapes, numbered as the conversion does."""
    counts, result = {}, {}
    for shape in shapes:
        number = counts[shape.group] = counts.get(shape.group, -1) + 1
        if shape.group in groups:
            result[(shape.group, number)] = (shape.kind, shape.position, shape.size)
    return result


def assert_same_drawing(markers, shapes):
    drawn, expected = marker_positions(markers), shape_positions(shapes)
    assert drawn.keys() == expected.keys()
    for key, (_, position, size) in expected.items():
        assert np.allclose(drawn[key][1], position, atol=1e-6), key
        assert np.allclose(drawn[key][2], size, atol=1e-12), key


def best_design(bag):
    """Return (task, physical design) of a run's best design, read from its bag."""
    record = records.open_run(bag)
    design = records.recorded_design(record, records.best_candidate_id(record))
    task = records.design_task(record, design)
    return task, design, genome_spec(task).decode(design.x)


@pytest.mark.system
def test_the_bag_holds_the_best_design_of_each_generation_as_markers(real_run, tmp_path):
    arrays = decoded_messages(real_run.mcap, contract.BEST_DESIGN)
    summaries = decoded_messages(real_run.mcap, contract.GENERATION_SUMMARY)
    assert len(arrays) == len(summaries) >= 2
    for array in arrays:
        assert array.markers[0].action == 3                        # DELETEALL first
        assert {m.header.frame_id for m in array.markers} == {contract.WORLD_FRAME}
    task, _, physical = best_design(real_run.bag)
    assert summaries[-1].final and summaries[-1].best_candidate_id == \
        real_run.result['best_candidate_id']
    assert_same_drawing(arrays[-1].markers, design_shapes(task, physical))
    # the object at its start is drawn too, and the bag still analyses
    assert any(m.ns == 'object' for m in arrays[-1].markers)
    assert main(['analyze', str(real_run.bag), '--out', str(tmp_path / 'report')]) == 0


@pytest.mark.system
def test_replay_writes_a_ros2_mcap_that_plays_the_rollout(real_run, tmp_path, capsys):
    out = tmp_path / 'rollout.mcap'
    assert main(['replay', str(real_run.bag), '--mcap', str(out)]) == 0
    assert 'bit for bit' in capsys.readouterr().out
    data = out.read_bytes()
    assert data.startswith(MCAP_MAGIC) and data.endswith(MCAP_MAGIC)    # closed: footer
    with open(out, 'rb') as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        assert reader.get_header().profile == 'ros2'
        summary = reader.get_summary()
        assert {schema.encoding for schema in summary.schemas.values()} == {'ros2msg'}
        assert {channel.message_encoding for channel in summary.channels.values()} == {'cdr'}
        schemas = {schema.name: schema.data.decode() for schema in summary.schemas.values()}
        assert set(schemas) == set(contract.REPLAY_TOPIC_TYPES.values())
        marker_schema = schemas[contract.MARKER_ARRAY_TYPE]
        for dependency in ('visualization_msgs/Marker', 'std_msgs/Header', 'geometry_msgs/Pose',
                           'std_msgs/ColorRGBA', 'builtin_interfaces/Time'):
            assert f'\nMSG: {dependency}\n' in marker_schema
        frames = {}
        for _, channel, message, decoded in reader.iter_decoded_messages():
            frames.setdefault(message.log_time, {})[channel.topic.lstrip('/')] = decoded
        # per frame markers, goal and joints; once the URDF and the palm (test_robot_view)
        assert summary.statistics.message_count == 3 * len(frames) + 2
    times = sorted(frames)
    assert times[0] == 0 and len(times) > 10
    assert np.allclose(np.diff(times), 40_000_000)                     # 25 frames per second
    assert set(frames[0]) == set(contract.REPLAY_TOPIC_TYPES)
    assert all(set(frame) == set(contract.REPLAY_TOPIC_TYPES) - {
        contract.ROBOT_DESCRIPTION, contract.TF_STATIC} for frame in list(frames.values())[1:])
    task, design, physical = best_design(real_run.bag)
    first = frames[times[0]][contract.REPLAY_MARKERS].markers
    last = frames[times[-1]][contract.REPLAY_MARKERS].markers
    assert_same_drawing(first, design_shapes(task, physical))         # the design as built
    moved = [np.subtract(marker_positions(last)[key][1], marker_positions(first)[key][1])
             for key in marker_positions(first) if key[0] == 'segments']
    assert max(np.linalg.norm(step) for step in moved) > 1e-3            # and then it moves
    goal = frames[times[-1]][contract.REPLAY_GOAL].pose.position
    _, position, _ = goal_poses(task, object_state(task, world_states(task)[0]))[-1]
    assert np.allclose((goal.x, goal.y, goal.z), position)
    from rosbags.highlevel import AnyReader
    with AnyReader([out]) as bag:
        decoded = [bag.deserialize(raw, connection.msgtype)
                   for connection, _, raw in bag.messages()]
    assert len(decoded) == 3 * len(frames) + 2
    assert sum(len(m.markers) for m in decoded if hasattr(m, 'markers')) == \
        sum(len(frame[contract.REPLAY_MARKERS].markers) for frame in frames.values())


@pytest.mark.system
def test_replay_mcap_refuses_a_bad_file_name_in_one_line(real_run, tmp_path, capsys):
    assert main(['replay', str(real_run.bag), '--mcap', str(tmp_path / 'x.bag')]) == 2
    error = capsys.readouterr().err
    assert error.count('\n') == 1 and 'ending in .mcap' in error


def layout_references(layout):
    """Return every (topic, field path) the layout's panels name."""
    references = []
    for panel, config in layout['configById'].items():
        for topic in config.get('topics', {}):
            references.append((topic, ''))
        paths = [path['value'] for path in config.get('paths', [])]
        if 'xAxisPath' in config:
            paths.append(config['xAxisPath']['value'])
        for path in paths:
            match = re.fullmatch(r'(/[\w/]+)(\{(\w+)==\$?\w+\})?\.(\w+)(\[\d+\])?', path)
            assert match, f'{panel}: message path {path!r} not understood'
            references.append((match.group(1), match.group(4)))
            if match.group(3):
                references.append((match.group(1), match.group(3)))
    return references


def test_the_layout_names_only_topics_and_fields_that_exist():
    layout = json.loads(LAYOUT.read_text())
    panels = set(layout['configById'])
    assert any(panel.startswith('3D!') for panel in panels)
    assert sum(panel.startswith('Plot!') for panel in panels) >= 2

    def leaves(node):
        return [node] if isinstance(node, str) else leaves(node['first']) + leaves(
            node['second'])
    assert sorted(leaves(layout['layout'])) == sorted(panels)
    from geometry_msgs.msg import PoseStamped
    classes = dict(topics.RECORDED_MESSAGE_TYPES, **{contract.REPLAY_MARKERS: topics.MarkerArray,
                                                     contract.REPLAY_GOAL: PoseStamped})
    references = layout_references(layout)
    named = {topic for topic, _ in references}
    assert {'/' + contract.BEST_DESIGN, '/' + contract.REPLAY_MARKERS,
            '/' + contract.GENERATION_SUMMARY, '/' + contract.EVALUATOR_STATUS} <= named
    for topic, field in references:
        assert topic.lstrip('/') in classes, f'{topic} is not a topic of the contract'
        if field:
            assert field in classes[topic.lstrip('/')].get_fields_and_field_types(), \
                f'{topic} has no field {field}'


# the keys Foxglove's classic layout file holds, and those of a Plot panel and its series
LAYOUT_KEYS = {'configById', 'globalVariables', 'userNodes', 'playbackConfig', 'layout'}
PANEL_TITLE = 'foxglovePanelTitle'   # where the app keeps a panel's title (not "title")
PLOT_KEYS = {PANEL_TITLE, 'paths', 'xAxisVal', 'xAxisPath', 'showLegend', 'legendDisplay',
             'showXAxisLabels', 'showYAxisLabels', 'isSynced', 'minYValue', 'maxYValue',
             'showPlotValuesInLegend', 'sidebarDimension'}
SERIES_KEYS = {'value', 'enabled', 'timestampMethod', 'label', 'color', 'showLine', 'lineSize'}


def test_the_layout_uses_the_keys_foxglove_reads():
    layout = json.loads(LAYOUT.read_text())
    assert set(layout) == LAYOUT_KEYS
    for panel, config in layout['configById'].items():
        assert 'title' not in config and config.get(PANEL_TITLE), f'{panel}: no panel title'
        if panel.startswith('Plot!'):
            assert set(config) <= PLOT_KEYS, (panel, set(config) - PLOT_KEYS)
            for series in config['paths']:
                assert set(series) <= SERIES_KEYS, (panel, set(series) - SERIES_KEYS)


def test_evaluator_plots_read_any_number_of_evaluators():
    # a line through every evaluator's statuses zig-zags between them, and a line per
    # evaluator needs a slot per id: the statuses of any number of evaluators are points
    layout = json.loads(LAYOUT.read_text())
    status = '/' + contract.EVALUATOR_STATUS
    series = [path for config in layout['configById'].values()
              for path in config.get('paths', []) if path['value'].startswith(status)]
    wanted = {f'{status}.steps_per_second', f'{status}.evaluations_done'}
    assert {path['value'] for path in series} >= wanted
    assert all(path['showLine'] is False and '{' not in path['value'] for path in series)
    assert layout['globalVariables'] == {}


# ------------------------------------------------------------------ live


async def watch_live(address, wanted, received, stop):
    """Subscribe to `wanted` topics of a Foxglove WebSocket server; collect messages."""
    from websockets.asyncio.client import connect
    async with connect(address, subprotocols=SUBPROTOCOLS,
                       max_size=None) as websocket:
        channels, subscribed = {}, {}
        while not stop.is_set():
            try:
                frame = await asyncio.wait_for(websocket.recv(), timeout=0.5)
            except asyncio.TimeoutError:
                continue
            except Exception:  # noqa: B902 the run ended and the server closed the connection
                return channels
            if isinstance(frame, str):
                message = json.loads(frame)
                if message['op'] == 'advertise':
                    news = [channel for channel in message['channels']
                            if channel['topic'] in wanted]
                    for channel in news:
                        channels[channel['id']] = channel
                        subscribed[len(subscribed) + 1] = channel['topic']
                    await websocket.send(json.dumps({'op': 'subscribe', 'subscriptions': [
                        {'id': number, 'channelId': channel['id']} for number, channel in
                        zip(range(len(subscribed) - len(news) + 1, len(subscribed) + 1),
                            news)]}))
            elif frame[0] == 1:                                           # message data
                subscription, _ = struct.unpack_from('<IQ', frame, 1)
                received.append((subscribed[subscription], bytes(frame[13:])))
        return channels


def listening_addresses(port):
    return {connection.laddr.ip for connection in psutil.net_connections(kind='tcp')
            if connection.status == psutil.CONN_LISTEN and connection.laddr.port == port}


@pytest.mark.system
def test_a_busy_port_stops_the_live_view_with_one_line():
    with socket.socket() as busy:
        busy.bind(('127.0.0.1', 0))
        busy.listen()
        port = busy.getsockname()[1]
        process = subprocess.run([sys.executable, '-m', 'hand_codesign.ros.live_node',
                                  '--ros-args', '-p', f'port:={port}'], cwd=ROOT,
                                 env=dict(os.environ, ROS_DOMAIN_ID='149'),
                                 capture_output=True, text=True, timeout=120)
    assert process.returncode == 2
    assert process.stderr.count('\n') == 1
    assert f'cannot serve on 127.0.0.1:{port}' in process.stderr, process.stderr


@pytest.mark.system
def test_a_live_run_is_served_to_foxglove_as_its_bag_records_it(tmp_path):
    bag = tmp_path / 'live'
    command = CLI + ['run', '--task', str(TASK), '--evaluators', '1', '--bag', str(bag),
                     '--domain-id', 'auto', *LIVE_BUDGET, '--live', '0']
    process = subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True)
    lines = queue.Queue()
    threading.Thread(target=lambda: [lines.put(line) for line in process.stdout] + [
        lines.put(None)], daemon=True).start()
    output = []
    while not output or not output[-1].startswith('live: '):
        line = lines.get(timeout=120)
        assert line is not None, ''.join(output)
        output.append(line)
    address = output[-1].split()[1]
    host, port = re.fullmatch(r'ws://([\d.]+):(\d+)', address).groups()
    assert host == '127.0.0.1' and listening_addresses(int(port)) == {'127.0.0.1'}
    wanted = {'/' + contract.GENERATION_SUMMARY, '/' + contract.BEST_DESIGN}
    received, stop = [], threading.Event()

    def wait_for_run():
        try:
            process.wait(timeout=240)
        finally:
            stop.set()
    threading.Thread(target=wait_for_run, daemon=True).start()
    channels = asyncio.run(watch_live(address, wanted, received, stop))
    process.wait(timeout=60)
    assert process.returncode == 0, ''.join(output) + ''.join(iter(lines.get, None))
    # the same schemas as the bag's, and every message byte for byte one the bag holds
    with open(next(bag.glob('*.mcap')), 'rb') as stream:
        summary = make_reader(stream).get_summary()
    bag_schemas = {schema.name: schema.data.decode() for schema in summary.schemas.values()}
    assert {channel['topic'] for channel in channels.values()} == wanted
    for channel in channels.values():
        assert channel['encoding'] == 'cdr' and channel['schemaEncoding'] == 'ros2msg'
        assert channel['schema'] == bag_schemas[channel['schemaName']]
    recorded = {(f'/{topic}', data) for topic, _, _, data in raw_messages(next(
        bag.glob('*.mcap')))}
    got = {topic for topic, _ in received}
    assert got == wanted, f'received only {got}'
    assert all(message in recorded for message in received)
