"""
The optimizer node: the run's RunController (hand_codesign.core.run.controller) over ROS 2.

It announces the run (RunInfo, latched), turns heartbeats and evaluations into controller
calls, and its candidates, summaries and best designs (markers) into messages (ros.keys signs).
"""

import sys

from hand_codesign.core.contract import STATUS_REJECTED
from hand_codesign.core.run.audits import DEFAULT_FRACTION
from hand_codesign.core.run.controller import default_run_id, RunController, write_result
from hand_codesign.core.run.dispatch import DispatchError
from hand_codesign.core.run.runs import load_run_task
from hand_codesign.core.task import TaskError
from hand_codesign.errors import UserError
from hand_codesign.ros import topics
from hand_codesign.ros.conversions import candidate_message
from hand_codesign.ros.conversions import markers_message
from hand_codesign.ros.conversions import stamp_now
from hand_codesign.ros.conversions import summary_message
from hand_codesign.ros.keys import OptimizerSigner
from hand_codesign.ros.node_main import on_line, run_node
from hand_codesign.ros.package_files import package_file
from hand_codesign.ros.parameters import declare_read_only
from hand_codesign.ros.topics import deliver
from hand_codesign_msgs.msg import RunInfo
from rclpy.event_handler import PublisherEventCallbacks
from rclpy.node import Node
from rclpy.task import Future

# name: (default, description, (lowest, highest) or None)
PARAMETERS = {
    'task_file': ('', 'task file (YAML); a relative one also in the package share/', None),
    'seed': (-1, "run seed; -1 keeps the task file's", (-1, 2**32 - 1)),
    'iterations': (0, "generations; 0 keeps the task file's (with resume_bag: the run's)",
                   (0, 10**6)),
    'population': (0, "candidates per generation; 0 keeps the task file's", (0, 10**5)),
    'world_states': (0, "randomized worlds per candidate; 0 keeps the task file's", (0, 10**6)),
    'engine': ('', "physics engines, e.g. pybullet,mujoco; empty keeps the task file's", None),
    'run_id': ('', 'id of the run; empty: made from the time and process id', None),
    'evaluators_expected': (1, 'evaluators to hear from before starting', (0, 10**4)),
    'subscribers_expected': (0, 'other subscribers (recorders) to wait for', (0, 100)),
    'heartbeat_timeout': (5.0, 's of evaluator silence before its candidates move', (0.1, 3600.0)),
    'evaluation_timeout': (0.0, 's before a candidate is sent again; 0: adaptive', (0.0, 86400.0)),
    'audit_fraction': (DEFAULT_FRACTION, 'share of answers audited (core.run.audits)', (0.0, 1.0)),
    'own_evaluators': ('', "roles of the run's own evaluators, a,b: see core.run.audits", None),
    'result_file': ('', 'write the final result as JSON here; empty: do not', None),
    'resume_bag': ('', 'continue the run of this bag (task, seed, budget: from the bag)', None),
    'start_signal': (False, 'send nothing before a line on stdin (the recorder records)', None),
}


class OptimizerNode(Node):
    """Carry the run's RunController over ROS 2; resuming reads the bag with `load_resume`."""

    def __init__(self, load_resume=None):
        super().__init__('optimizer')
        self.settings = declare_read_only(self, PARAMETERS)
        self.finished = Future()
        self.signer = OptimizerSigner.from_environment()
        resumed = None
        if self.settings['resume_bag']:  # the run in the bag fixes task, seed, budget
            if load_resume is None:
                raise UserError('parameter resume_bag: this entry point cannot read bags; start '
                                '`python -m hand_codesign.commands.optimizer` instead')
            resumed = load_resume(self.settings['resume_bag'], self.settings['iterations'])
            task = resumed.task
            self.log(resumed.describe())
        else:
            seed, path = self.settings['seed'], self.settings['task_file']
            task = load_run_task(package_file(path, 'parameter task_file'),
                                 None if seed < 0 else seed, self.settings['iterations'],
                                 self.settings['population'], self.settings['world_states'],
                                 self.settings['engine'])
        self.run = RunController(
            task, self.settings['run_id'] or default_run_id(task), self, resumed,
            self.settings['heartbeat_timeout'], self.settings['evaluation_timeout'],
            self.settings['evaluators_expected'], audit_fraction=self.settings['audit_fraction'],
            own_evaluators=filter(None, self.settings['own_evaluators'].split(',')))
        matched = PublisherEventCallbacks(matched=self.start_if_ready)
        self.publishers_ = {name: self.create_publisher(
            topics.RECORDED_MESSAGE_TYPES[name], name, topics.QOS[name], event_callbacks=matched)
            for name in topics.OPTIMIZER_TOPICS}
        self.published = dict.fromkeys(self.publishers_, 0)
        for name, callback in ((topics.EVALUATIONS, self.on_evaluation),
                               (topics.EVALUATOR_STATUS, self.on_status)):
            self.create_subscription(topics.MESSAGE_TYPES[name], name, callback, topics.QOS[name])
        self.publish(topics.RUN_INFO, self.signer.run_info(
            RunInfo(**self.run.run_info(), stamp=stamp_now(self))))
        self.log(self.run.describe() + self.signer.note)
        self.create_timer(0.2, self.tick)  # messages drive the run; this starts it
        self.signal = (on_line(sys.stdin, self, self.start_if_ready)
                       if self.settings['start_signal'] else None)

    def publish(self, topic, message):
        self.publishers_[topic].publish(message)
        self.published[topic] += 1

    def tick(self):
        wanted, signal = self.settings['subscribers_expected'], self.signal
        self.run.tick((signal is None or signal.is_set()) and all(
            p.get_subscription_count() >= wanted for p in self.publishers_.values()))

    def start_if_ready(self, *event):
        # the run starts on the heartbeat, match or signal that completes it, not at a tick
        if self.run.started is None:
            self.tick()

    def on_status(self, message):
        if self.signer.valid(message):  # no one speaks for an evaluator or invents one
            self.run.heard_from(message.evaluator_id, message.capacity, message.run_id)
        self.start_if_ready()

    def on_evaluation(self, message):
        key = message.run_id, message.candidate_id, message.evaluator_id
        if not self.signer.valid(message):
            self.run.forged(message.run_id, message.evaluator_id)
        elif message.status == STATUS_REJECTED:
            self.run.rejected(*key, message.reason)
        else:
            self.run.evaluated(*key, message.objectives, message.wall_time,
                               message.outcome_names, message.outcomes, evaluation=message)

    def send_candidate(self, candidate, evaluator_id, attempt, genome_names, design):
        self.publish(topics.CANDIDATES, self.signer.candidate(candidate_message(
            self.run.run_id, candidate, genome_names, evaluator_id, attempt, design)))

    def send_summary(self, summary):
        message = summary_message(self.run.run_id, summary)
        self.publish(topics.GENERATION_SUMMARY, self.signer.summary(message))
        self.publish(topics.BEST_DESIGN, markers_message(summary['best_design'], stamp_now(self)))

    def log(self, text, level='info'):  # 2 call sites: rclpy ties a severity to each
        self.get_logger().warning(text) if level == 'warning' else self.get_logger().info(text)

    def finish(self, result):
        deliver(self.publishers_.values(), self.settings['subscribers_expected'])
        if self.settings['result_file']:  # the published counts let tests check the bag
            write_result(self.settings['result_file'], result, self.published)
        self.finished.set_result(True)


def main(args=None, load_resume=None):
    return run_node(lambda: OptimizerNode(load_resume), 'optimizer', args,
                    errors=(TaskError, DispatchError), until=lambda node: node.finished)


if __name__ == '__main__':
    sys.exit(main())
