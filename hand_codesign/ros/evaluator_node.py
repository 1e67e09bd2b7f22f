"""
The evaluator node: evaluates candidates with hand_codesign.core.evaluate and answers them.

It learns the run's task from the latched RunInfo, takes the candidates addressed to it (or to
any evaluator), evaluates them one after another in a worker thread, so that its heartbeats go
on while PyBullet runs, and publishes an Evaluation for each. A candidate it cannot evaluate
gets a rejection with the reason, never a crash. A hardware evaluator would replace
`evaluate_candidate` and keep everything else.
"""

import os
import queue
import socket
import threading
import time

from hand_codesign.core import genome_spec
from hand_codesign.core.evaluate import evaluate
from hand_codesign.core.runs import run_task
from hand_codesign.ros import topics
from hand_codesign.ros.conversions import evaluation_message
from hand_codesign.ros.conversions import rejection_message
from hand_codesign.ros.conversions import stamp_now
from hand_codesign_msgs.msg import EvaluatorStatus
import numpy as np
from rcl_interfaces.msg import ParameterDescriptor
import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node

RUN_INFO_WAIT = 10.0


class CandidateRejected(Exception):
    """A candidate that cannot be evaluated; the message says why."""


class EvaluatorNode(Node):
    """Evaluate the candidates addressed to it and answer each with an Evaluation."""

    def __init__(self):
        super().__init__('evaluator')
        self.declare_parameter('evaluator_id', '', ParameterDescriptor(
            description='unique name of this evaluator; empty: <host>-<pid>'))
        self.declare_parameter('run_id', '', ParameterDescriptor(
            description='serve only this run; empty: every run it hears of'))
        self.declare_parameter('capacity', 2, ParameterDescriptor(
            description='candidates it asks to have queued at once'))
        self.declare_parameter('heartbeat_period', 0.5, ParameterDescriptor(
            description='seconds between status messages'))
        self.declare_parameter('subscribers_expected', 1, ParameterDescriptor(
            description='subscriptions to its evaluations (optimizer, recorders) to wait for '
                        'before it announces itself'))
        self.evaluator_id = (self.get_parameter('evaluator_id').value
                             or f'{socket.gethostname()}-{os.getpid()}')
        self.wanted_run = self.get_parameter('run_id').value
        self.capacity = self.get_parameter('capacity').value
        self.subscribers_expected = self.get_parameter('subscribers_expected').value

        self.runs = {}  # run id -> RunInfo message
        self.tasks = {}  # (run id, structure, world states) -> (Task, GenomeSpec)
        self.seen = set()  # (run id, candidate id, attempt) already queued
        self.done = 0
        self.steps_per_second = 0.0
        self.work = queue.Queue()
        self.busy = 0
        self.published = 0
        self.lock = threading.Lock()
        self.waiting = {}  # run id -> [(candidate, arrival time)] that overtook their RunInfo

        self.evaluations = self.create_publisher(
            topics.MESSAGE_TYPES[topics.EVALUATIONS], topics.EVALUATIONS,
            topics.QOS[topics.EVALUATIONS])
        self.status = self.create_publisher(
            EvaluatorStatus, topics.EVALUATOR_STATUS, topics.QOS[topics.EVALUATOR_STATUS])
        self.create_subscription(topics.MESSAGE_TYPES[topics.RUN_INFO], topics.RUN_INFO,
                                 self.on_run_info, topics.QOS[topics.RUN_INFO])
        self.create_subscription(topics.MESSAGE_TYPES[topics.CANDIDATES], topics.CANDIDATES,
                                 self.on_candidate, topics.QOS[topics.CANDIDATES])
        self.create_timer(self.get_parameter('heartbeat_period').value, self.publish_status)
        self.create_timer(1.0, self.drop_orphans)
        self.worker = threading.Thread(target=self.work_loop, daemon=True)
        self.worker.start()
        self.get_logger().info(f'evaluator {self.evaluator_id} ready')

    def on_run_info(self, message):
        if self.wanted_run and message.run_id != self.wanted_run:
            return
        self.runs[message.run_id] = message
        for candidate, _ in self.waiting.pop(message.run_id, []):
            self.enqueue(candidate)

    def on_candidate(self, message):
        if message.evaluator_id not in ('', self.evaluator_id):
            return
        if self.wanted_run and message.run_id != self.wanted_run:
            return
        key = (message.run_id, message.candidate_id, message.attempt)
        if key in self.seen:
            return
        self.seen.add(key)
        if message.run_id in self.runs:
            self.enqueue(message)
        else:
            # a candidate can overtake its run's RunInfo, which travels on another topic
            self.waiting.setdefault(message.run_id, []).append((message, time.monotonic()))

    def enqueue(self, message):
        with self.lock:
            self.busy += 1
        self.work.put(message)
        self.publish_status()

    def drop_orphans(self):
        """Queue for rejection the candidates whose RunInfo did not come in time."""
        now = time.monotonic()
        for run_id, waiting in list(self.waiting.items()):
            if now - waiting[0][1] > RUN_INFO_WAIT:
                for candidate, _ in self.waiting.pop(run_id):
                    self.enqueue(candidate)

    def work_loop(self):
        while rclpy.ok():
            try:
                message = self.work.get(timeout=0.2)
            except queue.Empty:
                continue
            started = time.perf_counter()
            try:
                answer = self.evaluate_candidate(message)
            except CandidateRejected as reason:
                answer = rejection_message(message, self.evaluator_id, str(reason))
            except Exception as error:  # noqa: B902 - a bad candidate must not kill the evaluator
                answer = rejection_message(message, self.evaluator_id,
                                           f'evaluation failed: {type(error).__name__}: {error}')
            answer.wall_time = time.perf_counter() - started
            if answer.simulated_time > 0:
                task, _ = self.tasks.get((message.run_id, tuple(message.structure),
                                          message.world_states, message.horizon), (None, None))
                steps = answer.simulated_time / task.time_step if task else 0.0
                self.steps_per_second = steps / max(answer.wall_time, 1e-9)
            self.evaluations.publish(answer)
            with self.lock:
                self.published += 1
                self.busy -= 1
                self.done += 1
            self.publish_status()

    def evaluate_candidate(self, message):
        """Return the Evaluation of a candidate; raise CandidateRejected if it is malformed."""
        task, spec = self.task_for(message)
        genome = np.asarray(message.genome, dtype=float)
        expected = spec.size
        if genome.shape != (expected,):
            raise CandidateRejected(
                f'genome has {genome.size} values, structure {tuple(message.structure)} of task '
                f'{task.name} needs {expected}')
        if not np.all(np.isfinite(genome)):
            raise CandidateRejected('genome contains NaN or infinite values')
        return evaluation_message(message, self.evaluator_id, evaluate(genome, task))

    def task_for(self, message):
        run = self.runs.get(message.run_id)
        if run is None:
            raise CandidateRejected(f'no RunInfo received for run "{message.run_id}"')
        key = (message.run_id, tuple(message.structure), message.world_states,
               message.horizon)
        if key not in self.tasks:
            try:
                task = run_task(
                    run.task_yaml, f'run {run.run_id} task', run.seed, run.iterations,
                    run.population, message.world_states or run.world_states,
                    tuple(message.structure) or None, message.horizon)
                self.tasks[key] = (task, genome_spec(task))
            except ValueError as error:
                raise CandidateRejected(f'unusable structure or task: {error}')
        return self.tasks[key]

    def publish_status(self):
        # Announcing itself only once every expected subscriber (the optimizer and the
        # recorder) has matched its evaluations makes sure the bag gets all of them, even
        # those of an evaluator killed right after its first answer.
        if self.evaluations.get_subscription_count() < self.subscribers_expected:
            return
        with self.lock:
            load = self.busy
            done = self.done
        self.status.publish(EvaluatorStatus(
            evaluator_id=self.evaluator_id, run_id=self.wanted_run,
            host=socket.gethostname(), pid=os.getpid(), capacity=self.capacity, load=load,
            evaluations_done=done, steps_per_second=float(self.steps_per_second),
            stamp=stamp_now(self)))


def main(args=None):
    rclpy.init(args=args)
    node = None
    try:
        node = EvaluatorNode()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
            print(f'{node.evaluator_id} published {node.published} evaluations', flush=True)
            node.destroy_node()
        rclpy.try_shutdown()


if __name__ == '__main__':
    main()
