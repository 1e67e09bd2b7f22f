"""
The rig evaluator node: evaluates candidates by trials on a test rig and answers them.

An evaluator like any other to the optimizer (same candidates, Evaluations and heartbeats);
what it decides is core.rig.trials.RigEvaluator's: for each world of a candidate it publishes a
TrialRequest on rig/trial_requests, hears the rig on rig/trial_status (started, ended, start
collision, failed), collects the object's geometry_msgs/PoseStamped on rig/object_pose and
scores the measured traces with the core's objectives. The recorder keeps all three rig
topics, so the bag holds every measured trace beside the run.
"""

import os
import socket
import sys
import time

from hand_codesign.core import contract
from hand_codesign.core.rig.trials import RigEvaluator
from hand_codesign.ros import topics
from hand_codesign.ros.conversions import evaluation_message
from hand_codesign.ros.conversions import rejection_message
from hand_codesign.ros.conversions import stamp_now
from hand_codesign.ros.conversions import trial_request
from hand_codesign.ros.keys import evaluator_credential
from hand_codesign.ros.keys import sign_evaluation, sign_status
from hand_codesign.ros.node_main import run_node
from hand_codesign.ros.parameters import declare_read_only
from hand_codesign_msgs.msg import EvaluatorStatus
from rclpy.node import Node

# name: (default, description, (lowest, highest) or None)
PARAMETERS = {
    'evaluator_id': ('', 'unique name of this evaluator; empty: rig-<host>-<pid>', None),
    'key_file': ('', 'key file (`hand-codesign run --write-key-file`); empty: none', None),
    'run_id': ('', 'serve only this run; empty: every run it hears of', None),
    'heartbeat_period': (0.5, 'seconds between status messages', (0.01, 60.0)),
    'start_timeout': (30.0, 'seconds for the rig to start a requested trial', (0.1, 3600.0)),
    'end_margin': (30.0, "seconds beyond a trial's duration for the rig to end it",
                   (0.1, 3600.0)),
    'max_gap': (0.1, 'seconds between two poses around a check: more is lost tracking',
                (1e-4, 10.0)),
    'settle': (1.0, 'seconds to wait for poses still in flight after a trial ended',
               (0.0, 60.0)),
    'subscribers_expected': (1, 'subscriptions to its evaluations to wait for before it '
                                'announces itself', (0, 100)),
}
LIMITS = ('start_timeout', 'end_margin', 'max_gap', 'settle')


def nanoseconds(stamp):
    """Return a builtin_interfaces/Time as integer nanoseconds."""
    return stamp.sec * 1_000_000_000 + stamp.nanosec


class RigEvaluatorNode(Node):
    """Evaluate the candidates addressed to it on a rig and answer each with an Evaluation."""

    def __init__(self):
        super().__init__('rig_evaluator')
        self.settings = declare_read_only(self, PARAMETERS)
        self.key, self.evaluator_id = evaluator_credential(self.settings)
        if self.key is None and not self.settings['evaluator_id']:
            self.evaluator_id = f'rig-{self.evaluator_id}'  # rig-<host>-<pid>
        self.rig = RigEvaluator(self.evaluator_id, self.settings['run_id'], self.key,
                                **{name: self.settings[name] for name in LIMITS})
        self.publishers_ = {name: self.create_publisher(
            topics.MESSAGE_TYPES[name], name, topics.QOS[name]) for name in (
            contract.EVALUATIONS, contract.EVALUATOR_STATUS, contract.TRIAL_REQUESTS)}
        for name, callback in ((contract.RUN_INFO, self.rig.run_announced),
                               (contract.CANDIDATES, self.rig.candidate_arrived),
                               (contract.TRIAL_STATUS, self.on_trial_status),
                               (contract.OBJECT_POSE, self.on_pose)):
            self.create_subscription(topics.MESSAGE_TYPES[name], name, callback,
                                     topics.QOS[name])
        self.create_timer(self.settings['heartbeat_period'], self.publish_status)
        self.create_timer(0.02, self.poll)
        self.get_logger().info(f'rig evaluator {self.evaluator_id} ready')

    def on_trial_status(self, message):
        if message.evaluator_id != self.evaluator_id:
            return
        if message.event == contract.TRIAL_STARTED:
            self.rig.started(message.trial_id, nanoseconds(message.stamp))
        elif message.event == contract.TRIAL_ENDED:
            self.rig.ended(message.trial_id, nanoseconds(message.stamp), time.monotonic())
        elif message.event == contract.TRIAL_START_COLLISION:
            self.rig.collided(message.trial_id)
        else:
            self.rig.failed(message.trial_id, message.reason)

    def on_pose(self, message):
        position, orientation = message.pose.position, message.pose.orientation
        self.rig.pose(nanoseconds(message.header.stamp),
                      (position.x, position.y, position.z),
                      (orientation.x, orientation.y, orientation.z, orientation.w))

    def poll(self):
        for action in self.rig.poll(time.monotonic()):
            kind, candidate = action[0], action[1]
            if kind == 'request':
                self.publishers_[contract.TRIAL_REQUESTS].publish(
                    trial_request(candidate, self.evaluator_id, action[2], action[3]))
                continue
            if kind == 'evaluated':
                answer = evaluation_message(candidate, self.evaluator_id, action[2])
                answer.wall_time, answer.measured = float(action[3]), True
            else:
                self.get_logger().warning(f'candidate {candidate.candidate_id}: {action[2]}')
                answer = rejection_message(candidate, self.evaluator_id, action[2])
            self.publishers_[contract.EVALUATIONS].publish(sign_evaluation(self.key, answer))
            self.publish_status()

    def publish_status(self):
        evaluations = self.publishers_[contract.EVALUATIONS]
        if evaluations.get_subscription_count() < self.settings['subscribers_expected']:
            return
        self.publishers_[contract.EVALUATOR_STATUS].publish(sign_status(self.key, EvaluatorStatus(
            evaluator_id=self.evaluator_id, run_id=self.settings['run_id'],
            host=socket.gethostname(), pid=os.getpid(), capacity=1, load=self.rig.load(),
            evaluations_done=self.rig.done, stamp=stamp_now(self))))


def main(args=None):
    return run_node(RigEvaluatorNode, 'rig_evaluator', args)


if __name__ == '__main__':
    sys.exit(main())
