"""
The evaluator node: evaluates candidates with hand_codesign.core.evaluate and answers them.

Which candidates it takes and what it evaluates are core.run.evaluation_jobs' rules; it answers
each candidate taken with an Evaluation or a rejection with the reason, never a crash; with a
key (ros.keys) it takes only signed messages and signs its answers. Named after its evaluator
id, two started alike do not clash. One thread does it all: between candidates and worlds
(every POLL_PERIOD at most) it takes what arrived and beats the heartbeat (a
MultiThreadedExecutor was 25 % slower). It ends with its runner, or optimizer_timeout s after
the optimizer of its run left (ros.lifeline).
"""

import collections
import os
import socket
import sys
import time

from hand_codesign.core.evaluate import evaluate
from hand_codesign.core.run.evaluation_jobs import CandidateRejected, EvaluatorInbox
from hand_codesign.core.run.supervision import node_name
from hand_codesign.ros import topics
from hand_codesign.ros.conversions import evaluation_message, rejection_message, stamp_now
from hand_codesign.ros.keys import evaluator_credential
from hand_codesign.ros.keys import sign_evaluation, sign_status
from hand_codesign.ros.lifeline import watch_optimizer
from hand_codesign.ros.node_main import run_node, take_arrived
from hand_codesign.ros.parameters import declare_read_only
from hand_codesign.ros.parameters import overrides
from hand_codesign.ros.parameters import read_before_start
from hand_codesign_msgs.msg import EvaluatorStatus
import rclpy
from rclpy.event_handler import PublisherEventCallbacks
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node

# name: (default, description, (lowest, highest) or None)
PARAMETERS = {
    'evaluator_id': ('', 'unique name of this evaluator; empty: <host>-<pid>', None),
    'key_file': ('', 'key file (`hand-codesign run --write-key-file`); empty: none', None),
    'run_id': ('', 'serve only this run; empty: every run it hears of', None),
    'capacity': (2, 'candidates it asks to have queued at once', (1, 1000)),
    'heartbeat_period': (0.5, 'seconds between status messages', (0.01, 60.0)),
    'subscribers_expected': (1, 'evaluation subscribers to wait for before announcing', (0, 100)),
    'optimizer_timeout': (60.0, 's a run may lack its optimizer; 0: no limit', (0.0, 1e6)),
}
IDLE_WAIT = 0.1  # s an idle evaluator waits for something to arrive
POLL_PERIOD = 0.05  # s between looks at the executor while evaluating (a Task 5 world: 5 ms)


class EvaluatorNode(Node):
    """Evaluate the candidates addressed to it and answer each with an Evaluation."""

    def __init__(self):
        settings = read_before_start('evaluator', PARAMETERS)
        self.key, self.evaluator_id = evaluator_credential(settings)
        super().__init__(node_name(self.evaluator_id), parameter_overrides=overrides(settings))
        self.settings = declare_read_only(self, PARAMETERS)
        self.inbox = EvaluatorInbox(self.evaluator_id, settings['run_id'], credential=self.key)
        self.work = collections.deque()  # candidates taken; the first is being evaluated
        self.done, self.steps_per_second = 0, 0.0
        # the first heartbeat goes out the moment the subscribers match, not a period later
        matched = PublisherEventCallbacks(matched=lambda status: self.publish_status())
        self.evaluations, self.status = (self.create_publisher(
            topics.MESSAGE_TYPES[name], name, topics.QOS[name], event_callbacks=matched)
            for name in (topics.EVALUATIONS, topics.EVALUATOR_STATUS))
        for name, callback in (
                (topics.RUN_INFO, lambda m: self.work.extend(self.inbox.run_announced(m))),
                (topics.CANDIDATES, lambda m: self.work.extend(self.inbox.candidate_arrived(m)))):
            self.create_subscription(topics.MESSAGE_TYPES[name], name, callback, topics.QOS[name])
        self.create_timer(self.settings['heartbeat_period'], self.publish_status)
        self.create_timer(1.0, lambda: self.work.extend(self.inbox.orphans()))
        watch_optimizer(self, topics.CANDIDATES, self.settings['optimizer_timeout'])
        self.last_poll = time.monotonic()
        self.get_logger().info(f'evaluator {self.evaluator_id} ready')

    def spin(self, executor):
        """Evaluate what is queued, else wait for the executor's callbacks; until shutdown."""
        while self.context.ok():
            if self.work:
                self.work_off()
            else:
                self.take_arrived(IDLE_WAIT)

    def poll(self, *_):
        """Let the executor handle what arrived meanwhile, at most every POLL_PERIOD."""
        now = time.monotonic()
        if now - self.last_poll >= POLL_PERIOD:
            self.last_poll = now
            self.take_arrived(0.0)

    def take_arrived(self, timeout):
        """Take every message that arrived (waiting up to timeout s for the first one)."""
        take_arrived(self.executor, lambda: self.inbox.heard, timeout)

    def work_off(self):
        """Evaluate and answer the first queued candidate (unless ROS shuts down meanwhile)."""
        answer = self.answer(self.work[0])
        if not self.context.ok():
            return
        self.evaluations.publish(sign_evaluation(self.key, answer))
        self.work.popleft()
        self.done += 1
        self.take_arrived(0.0)
        if not self.work:  # idle: say so (and the final count) now, not at the next beat
            self.publish_status()

    def answer(self, message):
        """Return the Evaluation answering a candidate: its objectives, or a rejection."""
        started = time.perf_counter()
        try:
            job = self.inbox.job(message)
            answer = evaluation_message(message, self.evaluator_id,
                                        evaluate(job.genome, job.task, job.worlds,
                                                 on_world=self.poll, share=job.share))
        except CandidateRejected as reason:
            answer = rejection_message(message, self.evaluator_id, str(reason))
        except ExternalShutdownException:  # heard while polling between worlds
            raise
        except Exception as error:  # noqa: B902 - a bad candidate must not kill the evaluator
            answer = rejection_message(message, self.evaluator_id,
                                       f'evaluation failed: {type(error).__name__}: {error}')
        answer.wall_time = time.perf_counter() - started
        if answer.simulated_time > 0:  # physics steps per wall second
            self.steps_per_second = answer.simulated_time / job.task.time_step / answer.wall_time
        return answer

    def publish_status(self):
        # announced once the optimizer and the recorder match, the bag gets all its evaluations
        if self.evaluations.get_subscription_count() < self.settings['subscribers_expected']:
            return
        self.status.publish(sign_status(self.key, EvaluatorStatus(
            evaluator_id=self.evaluator_id, run_id=self.settings['run_id'],
            host=socket.gethostname(), pid=os.getpid(), capacity=self.settings['capacity'],
            load=len(self.work), evaluations_done=self.done, rejected_messages=self.inbox.rejected,
            steps_per_second=float(self.steps_per_second), stamp=stamp_now(self))))


def farewell(node):
    # the node's logger would also publish to /rosout, whose context is gone by now
    rclpy.logging.get_logger('evaluator').info(
        f'{node.evaluator_id} published {node.done} evaluations')


def main(args=None):
    return run_node(EvaluatorNode, 'evaluator', args, farewell=farewell, spin=EvaluatorNode.spin)


if __name__ == '__main__':
    sys.exit(main())
