"""
The re-evaluation node: sends recorded designs once more, to a simulation and a rig evaluator.

`hand-codesign evaluate BAG --rig` starts it with a plan (hand_codesign.core.rig.reevaluation):
it announces the plan's run (RunInfo, latched), waits for `evaluators_expected` evaluators'
heartbeats, sends every candidate once to any evaluator (with its design in physical terms,
as the optimizer sends it) and ends once each has a simulated and a measured answer, or
after `timeout` seconds with the missing ones named.
"""

import pathlib
import sys
import time

from hand_codesign.core.rig.reevaluation import AnswerBook, read_plan
from hand_codesign.core.run.runs import run_task
from hand_codesign.core.sim.physical import candidate_design
from hand_codesign.ros import topics
from hand_codesign.ros.conversions import candidate_message
from hand_codesign.ros.conversions import stamp_now
from hand_codesign.ros.lifeline import follow_runner
from hand_codesign.ros.parameters import declare_read_only
from hand_codesign_msgs.msg import RunInfo
import rclpy
from rclpy.exceptions import ParameterException
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.task import Future

PARAMETERS = {
    'plan_file': ('', 'the plan (JSON) written by hand-codesign evaluate', None),
    'evaluators_expected': (2, 'evaluators to hear from before sending', (1, 100)),
    'timeout': (3600.0, 'seconds to wait for every answer', (1.0, 10 ** 6)),
}


class ReevaluationNode(Node):
    """Send a plan's candidates and wait for their simulated and measured answers."""

    def __init__(self):
        super().__init__('optimizer')
        self.settings = declare_read_only(self, PARAMETERS)
        self.run_fields, self.planned = read_plan(
            pathlib.Path(self.settings['plan_file']).read_text(encoding='utf-8'))
        self.book = AnswerBook(candidate.candidate_id for candidate in self.planned)
        self.heard = set()
        self.sent = False
        self.finished = Future()
        self.deadline = time.monotonic() + self.settings['timeout']
        self.publishers_ = {name: self.create_publisher(
            topics.MESSAGE_TYPES[name], name, topics.QOS[name])
            for name in (topics.RUN_INFO, topics.CANDIDATES)}
        self.create_subscription(topics.MESSAGE_TYPES[topics.EVALUATIONS], topics.EVALUATIONS,
                                 self.on_evaluation, topics.QOS[topics.EVALUATIONS])
        self.create_subscription(topics.MESSAGE_TYPES[topics.EVALUATOR_STATUS],
                                 topics.EVALUATOR_STATUS, self.on_status,
                                 topics.QOS[topics.EVALUATOR_STATUS])
        self.publishers_[topics.RUN_INFO].publish(RunInfo(**self.run_fields,
                                                          stamp=stamp_now(self)))
        self.create_timer(0.2, self.tick)
        self.get_logger().info(f're-evaluating {len(self.planned)} designs of run '
                               f'{self.run_fields["resumed_from"]} as run '
                               f'{self.run_fields["run_id"]}')

    def on_status(self, message):
        self.heard.add(message.evaluator_id)

    def on_evaluation(self, message):
        if message.run_id == self.run_fields['run_id']:
            self.book.answered(message.candidate_id, message.measured)
            kind = 'measured' if message.measured else 'simulated'
            self.get_logger().info(f'candidate {message.candidate_id}: {kind} by '
                                   f'{message.evaluator_id}' + (
                                       f', rejected: {message.reason}' if message.reason
                                       else ''))

    def tick(self):
        if not self.sent and len(self.heard) >= self.settings['evaluators_expected']:
            self.send_all()
        if self.book.done:
            self.finished.set_result(0)
        elif time.monotonic() > self.deadline:
            self.get_logger().error(f'timeout: {self.book.describe()}')
            self.finished.set_result(1)

    def send_all(self):
        fields = self.run_fields
        for candidate in self.planned:
            task = run_task(fields['task_yaml'], f'run {fields["run_id"]} task', fields['seed'],
                            fields['iterations'], fields['population'], fields['world_states'],
                            candidate.variant)
            self.publishers_[topics.CANDIDATES].publish(candidate_message(
                fields['run_id'], candidate, candidate.genome_names, '', 0,
                candidate_design(task, candidate.x)))
        self.sent = True


def main(args=None):
    follow_runner()
    rclpy.init(args=args)
    node = None
    code = 1
    try:
        node = ReevaluationNode()
        rclpy.spin_until_future_complete(node, node.finished)
        code = node.finished.result() if node.finished.done() else 130
    except (KeyboardInterrupt, ExternalShutdownException):
        code = 130
    except (ParameterException, OSError, ValueError) as error:
        rclpy.logging.get_logger('optimizer').error(str(error))
        code = 2
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return code


if __name__ == '__main__':
    sys.exit(main())
