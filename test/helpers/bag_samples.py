"""Sample loop messages, bags written from them, and ROS process helpers for the bag tests."""

import os
import pathlib
import subprocess
import sys
import threading
import time

from geometry_msgs.msg import PoseStamped
from hand_codesign.bag import cdr
from hand_codesign.bag.writer import BagWriter
from hand_codesign.bag.writer import message_definition
from hand_codesign.ros import topics
from hand_codesign_msgs.msg import Candidate
from hand_codesign_msgs.msg import Evaluation
from hand_codesign_msgs.msg import EvaluatorStatus
from hand_codesign_msgs.msg import GenerationSummary
from hand_codesign_msgs.msg import RunInfo
from hand_codesign_msgs.msg import TrialRequest
from hand_codesign_msgs.msg import TrialStatus
from mcap.reader import make_reader
import numpy as np
from rclpy.serialization import serialize_message
import yaml

ROOT = pathlib.Path(__file__).resolve().parents[2]
TASK_YAML = (ROOT / 'config' / 'tasks' / 'task5.yaml').read_text() + '# ünïcödé comment\n'
OBJECTIVES = ['position_1', 'orientation_1']


def sample_messages(run_id='run-1', generations=3, population=12, worlds=3, seed=0):
    """Return {topic: [message, ...]} of a small run, every field filled, one rejection."""
    rng = np.random.default_rng(seed)
    genome_names = [f'finger{f}.segment{s}.length' for f in range(2) for s in range(3)]
    run_info = RunInfo(
        run_id=run_id, task_name='task5', task_yaml=TASK_YAML, seed=4, algorithm='cma',
        iterations=generations, population=population, world_states=worlds,
        objective_names=OBJECTIVES, versions=['hand_codesign==0.1.0', 'numpy==2.4.6'],
        resumed_from='')
    run_info.stamp.sec = 1_700_000_000
    run_info.stamp.nanosec = 123
    candidates, evaluations, summaries = [], [], []
    for generation in range(generations):
        for index in range(population):
            candidate_id = generation * population + index
            genome = rng.random(len(genome_names))
            candidates.append(Candidate(
                run_id=run_id, generation=generation, candidate_id=candidate_id,
                evaluator_id='', attempt=0, structure=[2, 2], genome=genome.tolist(),
                genome_names=genome_names, design_names=['hand.friction'],
                design_values=[0.5 + index], hand_urdf='<robot name="hand"/>',
                controller_kind='torque', controller_mode='constant',
                controller_knot_times=[0.0, 0.5], controller_values=[0.1] * 8))
            if candidate_id == 5:
                evaluations.append(Evaluation(
                    run_id=run_id, generation=generation, candidate_id=candidate_id,
                    evaluator_id='host-7', status=Evaluation.STATUS_REJECTED,
                    reason='genome has NaN — rejected', wall_time=0.001))
                continue
            world = rng.random((worlds, len(OBJECTIVES)))
            objectives = world.mean(axis=0)
            evaluations.append(Evaluation(
                run_id=run_id, generation=generation, candidate_id=candidate_id, attempt=0,
                evaluator_id=f'host-{index % 2}', status=Evaluation.STATUS_OK,
                objectives=objectives.tolist(), objective_names=OBJECTIVES,
                fitness=float(objectives @ [1.0, 0.1]), collision=bool(index == 3),
                unstable_worlds=index % 3, simulated_time=2.5 * worlds, wall_time=0.2,
                world_objectives=world.ravel().tolist(), measured=index == 4))
        summaries.append(GenerationSummary(
            run_id=run_id, generation=generation, structure=[2, 2],
            objective_names=OBJECTIVES, best=[0.1, 0.2], median=[0.3, 0.4], worst=[0.5, 0.6],
            pareto_size=0, pareto_front=[], best_candidate_id=generation * population,
            best_objectives=[0.1, 0.2], best_fitness=0.12, best_genome=[0.5] * 6,
            evaluations=(generation + 1) * population, wall_time=1.5 * generation,
            final=generation == generations - 1,
            stop_reason='iterations' if generation == generations - 1 else ''))
    statuses = [EvaluatorStatus(evaluator_id=f'{run_id}-host-{index % 2}',
                                run_id=run_id if index else '',
                                host='host', pid=100 + index % 2, capacity=2, load=index % 3,
                                evaluations_done=index, steps_per_second=25000.0)
                for index in range(7)]
    return {topics.RUN_INFO: [run_info], topics.CANDIDATES: candidates,
            topics.EVALUATIONS: evaluations, topics.EVALUATOR_STATUS: statuses,
            topics.GENERATION_SUMMARY: summaries, **rig_messages(run_id)}


def rig_messages(run_id):
    """Return {topic: [message, ...]} of one trial on a rig: request, events, two poses."""
    request = TrialRequest(
        run_id=run_id, candidate_id=4, attempt=0, evaluator_id='rig', trial_id=1, world=0,
        worlds=1, object_shape='box', object_size=[0.1, 0.1, 0.1], object_scale=1.0,
        object_position=[0.0, 0.0, 0.05], object_orientation=[0.0, 0.0, 0.0, 1.0],
        object_mass=0.2, object_friction=0.8, duration=1.5)
    events = [TrialStatus(rig_id='sim_rig', trial_id=1, evaluator_id='rig', event=event)
              for event in (TrialStatus.EVENT_STARTED, TrialStatus.EVENT_ENDED)]
    events[1].stamp.sec = 2
    poses = []
    for second in (0, 2):
        pose = PoseStamped()
        pose.header.stamp.sec = second
        pose.header.frame_id = 'world'
        pose.pose.position.z = 0.05 + second
        pose.pose.orientation.w = 1.0
        poses.append(pose)
    return {topics.TRIAL_REQUESTS: [request], topics.TRIAL_STATUS: events,
            topics.OBJECT_POSE: poses}


def interleaved(messages_by_topic):
    """Return (topic, message) pairs, the topics taking turns as in a real run."""
    queues = {topic: list(messages) for topic, messages in messages_by_topic.items()}
    pairs = []
    while any(queues.values()):
        for topic, queue in queues.items():
            if queue:
                pairs.append((topic, queue.pop(0)))
    return pairs


_DECODERS = {}


def dds_bytes(message):
    """
    Return a message serialized as DDS delivers it to a raw subscription.

    rclpy's serialize_message reports the estimated size, 4 bytes too long for a message
    ending in an empty float64[] (a rejected Evaluation); DDS sends the real length, padded
    to 4 bytes. Strict readers (rosbags) reject the longer form.
    """
    data = serialize_message(message)
    type_name = topics.type_name(type(message))
    if type_name not in _DECODERS:
        _DECODERS[type_name] = cdr.compile_schema(type_name, message_definition(type_name))
    end = _DECODERS[type_name].message_end(data)
    return data[:4 + ((end - 4 + 3) & ~3)]


def write_bag(path, messages_by_topic, flush_every=None, close=True):
    """Write the messages to a bag at path with BagWriter; return the writer."""
    writer = BagWriter(path)
    for topic in messages_by_topic:
        message_class = topics.MESSAGE_TYPES[topic]
        writer.add_topic('/' + topic, topics.type_name(message_class), [topics.QOS[topic]])
    for index, (topic, message) in enumerate(interleaved(messages_by_topic)):
        writer.write('/' + topic, dds_bytes(message), log_time=1_000_000 + index)
        if flush_every and (index + 1) % flush_every == 0:
            writer.flush()
    if close:
        writer.close()
    return writer


def ros_env(domain_id):
    """Return the environment of a ROS process isolated on domain_id and this host."""
    env = dict(os.environ)
    env.update(ROS_DOMAIN_ID=str(domain_id), ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST',
               AMENT_PREFIX_PATH=sys.prefix, PYTHONUNBUFFERED='1')
    return env


class Process:
    """A child process whose stderr and stdout are collected by a thread (no pipe stalls)."""

    def __init__(self, args, env, cwd=None):
        """Start args."""
        self.popen = subprocess.Popen(args, env=env, cwd=cwd, stdout=subprocess.PIPE,
                                      stderr=subprocess.STDOUT, text=True)
        self.lines = []
        self._reader = threading.Thread(target=self._collect, daemon=True)
        self._reader.start()

    def _collect(self):
        for line in self.popen.stdout:
            self.lines.append(line)

    @property
    def output(self):
        """Return everything the process printed so far."""
        return ''.join(self.lines)

    def wait_for_line(self, text, timeout):
        """Wait until a printed line contains text; return whether it did in time."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if any(text in line for line in self.lines):
                return True
            if self.popen.poll() is not None:
                self._reader.join(timeout=1.0)
                return any(text in line for line in self.lines)
            time.sleep(0.05)
        return False

    def wait(self, timeout):
        """Wait for the exit; return the exit code."""
        code = self.popen.wait(timeout=timeout)
        self._reader.join(timeout=2.0)
        return code

    def stop(self):
        """Kill the process if it still runs (test clean-up)."""
        if self.popen.poll() is None:
            self.popen.kill()
            self.popen.wait(timeout=10)
        self._reader.join(timeout=2.0)


def rosbag2_record(path):
    """Return the BagMetadata of an MCAP file's "rosbag2" record, read as rosbag2 reads it."""
    with open(path, 'rb') as stream:
        records = [record for record in make_reader(stream).iter_metadata()
                   if record.name == 'rosbag2']
    assert len(records) == 1, f'{path}: {len(records)} rosbag2 metadata records'
    return yaml.safe_load(records[0].metadata['serialized_metadata'])
