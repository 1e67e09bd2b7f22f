"""
The optimizer node: drives the ask/tell search one generation at a time over ROS 2.

It announces the run (RunInfo, latched), waits for evaluators (and a recorder, when asked
to), sends each candidate to one evaluator through a Dispatcher, collects every evaluation
by candidate id, tells the optimizer once per generation, publishes a GenerationSummary, and
ends with the final summary and, when asked, a result file.
"""

import collections
import json
import os
import sys
import time

from hand_codesign.core import genome_spec
from hand_codesign.core.dispatch import Dispatcher
from hand_codesign.core.dispatch import DispatchError
from hand_codesign.core.runs import library_versions
from hand_codesign.core.runs import load_run_task
from hand_codesign.core.search import Search
from hand_codesign.core.summary import generation_summary
from hand_codesign.core.summary import progress_line
from hand_codesign.core.task import TaskError
from hand_codesign.errors import UserError
from hand_codesign.ros import topics
from hand_codesign.ros.conversions import candidate_message
from hand_codesign.ros.conversions import stamp_now
from hand_codesign.ros.conversions import summary_message
from hand_codesign_msgs.msg import Evaluation
from hand_codesign_msgs.msg import RunInfo
import numpy as np
from rcl_interfaces.msg import ParameterDescriptor
import rclpy
from rclpy.duration import Duration
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.task import Future

PARAMETERS = {
    'task_file': ('', 'task file (YAML) to optimize'),
    'seed': (-1, "run seed; -1 keeps the task file's"),
    'iterations': (0, "generations; 0 keeps the task file's"),
    'population': (0, "candidates per generation; 0 keeps the task file's"),
    'world_states': (0, "randomized worlds per candidate; 0 keeps the task file's"),
    'run_id': ('', 'id of the run; empty: made from the time and process id'),
    'evaluators_expected': (1, 'evaluators to hear from before the first generation'),
    'subscribers_expected': (0, 'subscriptions besides evaluators (recorders) to wait for'),
    'heartbeat_timeout': (5.0, 'seconds of evaluator silence before its candidates move on'),
    'evaluation_timeout': (0.0, 'seconds before a candidate is sent again; 0: adaptive'),
    'result_file': ('', 'write the final result as JSON here; empty: do not'),
    'resume_bag': ('', 'continue the interrupted run of this bag (its task, seed and budget; '
                       'task_file and the budget parameters are then ignored)'),
}


class OptimizerNode(Node):
    """Drive the run's search over the evaluators, one generation at a time."""

    def __init__(self):
        super().__init__('optimizer')
        for name, (default, description) in PARAMETERS.items():
            self.declare_parameter(name, default, ParameterDescriptor(description=description))
        self.finished = Future()
        self.resumed = None
        if self.param('resume_bag'):
            # the search replayed from the bag up to the interruption (core.optimizers.replay);
            # imported here: reading bags is not needed to start a new run
            from hand_codesign.analysis.resume import resume_point
            self.resumed = resume_point(self.param('resume_bag'))
            self.task = self.resumed.task
            self.search = self.resumed.search
            self.told = self.resumed.evaluations_told
            self.get_logger().info(self.resumed.describe())
        else:
            seed = self.param('seed')
            self.task = load_run_task(self.param('task_file'), None if seed < 0 else seed,
                                      self.param('iterations'), self.param('population'),
                                      self.param('world_states'))
            self.search = Search(self.task)
            self.told = 0
        self.run_id = (self.param('run_id')
                       or f'{self.task.name}-{time.strftime("%Y%m%d-%H%M%S")}-{os.getpid()}')
        self.batch = None
        self.dispatcher = Dispatcher(self.param('heartbeat_timeout'),
                                     self.param('evaluation_timeout') or 3600.0)
        self.adaptive_timeout = self.param('evaluation_timeout') <= 0
        self.results = {}
        self.last_summary = None
        self.wall_times = collections.deque(maxlen=50)
        self.started = None

        self.publishers_ = {
            name: self.create_publisher(topics.MESSAGE_TYPES[name], name, topics.QOS[name])
            for name in (topics.RUN_INFO, topics.CANDIDATES, topics.GENERATION_SUMMARY)}
        self.create_subscription(Evaluation, topics.EVALUATIONS, self.on_evaluation,
                                 topics.QOS[topics.EVALUATIONS])
        self.create_subscription(topics.MESSAGE_TYPES[topics.EVALUATOR_STATUS],
                                 topics.EVALUATOR_STATUS, self.on_status,
                                 topics.QOS[topics.EVALUATOR_STATUS])
        self.published = dict.fromkeys(self.publishers_, 0)
        self.publish(topics.RUN_INFO, self.run_info())
        self.get_logger().info(
            f'run {self.run_id}: task {self.task.name}, {self.task.algorithm}, '
            f'{self.task.iterations} generations x {self.task.population}, '
            f'{self.task.num_world_states} world states, seed {self.task.seed}; '
            f'waiting for {self.param("evaluators_expected")} evaluator(s)')
        # Evaluations and heartbeats drive the run; the timer only starts it and catches
        # silent evaluators and overdue candidates, so the node costs no CPU while it waits.
        self.create_timer(0.2, self.tick)

    def param(self, name):
        return self.get_parameter(name).value

    def publish(self, topic, message):
        self.publishers_[topic].publish(message)
        self.published[topic] += 1

    def run_info(self):
        task = self.task
        return RunInfo(
            run_id=self.run_id, task_name=task.name, task_yaml=task.source_text,
            seed=task.seed, algorithm=task.algorithm, iterations=task.iterations,
            population=task.population, world_states=task.num_world_states,
            objective_names=list(task.objective_names), versions=library_versions(),
            resumed_from=self.resumed.run_id if self.resumed is not None else '',
            stamp=stamp_now(self))

    def on_status(self, message):
        if message.run_id in ('', self.run_id):
            self.dispatcher.heard_from(message.evaluator_id, message.capacity, time.monotonic())
            self.advance()

    def on_evaluation(self, message):
        if message.run_id != self.run_id:
            return
        if message.status == Evaluation.STATUS_REJECTED:
            if self.dispatcher.reject(message.candidate_id, message.evaluator_id, message.reason):
                self.get_logger().warning(
                    f'candidate {message.candidate_id} rejected by {message.evaluator_id}: '
                    f'{message.reason}')
            return
        if self.dispatcher.complete(message.candidate_id, message.evaluator_id):
            self.results[message.candidate_id] = np.array(message.objectives, dtype=float)
            self.wall_times.append(message.wall_time)
            self.advance()

    def ready_to_start(self):
        now = time.monotonic()
        enough_evaluators = (len(self.dispatcher.live_evaluators(now))
                             >= self.param('evaluators_expected'))
        wanted = self.param('subscribers_expected')
        matched = all(publisher.get_subscription_count() >= wanted
                      for publisher in self.publishers_.values())
        return enough_evaluators and matched

    def tick(self):
        if self.started is None and self.ready_to_start():
            self.started = time.monotonic()
            self.get_logger().info('evaluators ready, starting')
        self.advance()

    def advance(self):
        """Send what can be sent; tell the batch when complete and start the next one."""
        if self.started is None or self.finished.done():
            return
        if self.batch is None:
            if self.search.stop():
                self.finish()
                return
            self.start_batch()
        if self.adaptive_timeout and self.wall_times:
            self.dispatcher.evaluation_timeout = max(60.0, 20.0 * max(self.wall_times))
        for candidate, evaluator_id, attempt in self.dispatcher.assignments(time.monotonic()):
            message = candidate_message(self.run_id, candidate, candidate.structure,
                                        self.batch_genome_names, evaluator_id, attempt)
            if self.search.checking:
                message.world_states = self.search.batch_task.num_world_states
            self.publish(topics.CANDIDATES, message)
        if self.dispatcher.unfinished == 0:
            self.tell_batch()
            self.advance()

    def start_batch(self):
        self.batch = self.search.ask()
        self.batch_genome_names = genome_spec(self.search.batch_task).names
        # a resumed run's first batch may be partly evaluated already (in the bag)
        known = self.resumed.known if self.resumed is not None else {}
        self.results = {candidate.candidate_id: known[candidate.candidate_id]
                        for candidate in self.batch if candidate.candidate_id in known}
        self.dispatcher.add([candidate for candidate in self.batch
                             if candidate.candidate_id not in self.results])

    def tell_batch(self):
        checking = self.search.checking
        structure = self.search.batch_task.structure
        optimizer = self.search.optimizer
        self.search.tell(self.results)
        self.told += len(self.batch)
        told_ids = [candidate.candidate_id for candidate in self.batch]
        objectives = np.array([self.results[candidate_id] for candidate_id in told_ids])
        generation = self.batch[0].generation
        self.batch = None
        summary = generation_summary(
            generation, structure, self.task.objective_names, told_ids, objectives,
            optimizer.result, self.told, time.monotonic() - self.started, checking)
        self.publish(topics.GENERATION_SUMMARY, summary_message(self.run_id, summary))
        if checking:
            self.get_logger().info(
                f'structure {list(structure)}: best design on the evaluation worlds: '
                + ', '.join(f'{name} {value:.4g}'
                            for name, value in zip(self.task.objective_names, objectives[0])))
            return
        self.last_summary = summary
        elapsed = time.monotonic() - self.started
        done = optimizer.generation
        left = elapsed / done * (self.task.iterations - done)
        self.get_logger().info(progress_line(summary, self.task.iterations,
                                             self.told / elapsed, left))

    def finish(self):
        stop_reason = ', '.join(f'{key}={value}' for key, value in self.search.stop().items())
        result, structure = self.search.best
        # after a resume, the last batch may have been a hierarchy check: no generation yet
        last = self.last_summary or generation_summary(
            self.search.optimizer.generation, structure, self.task.objective_names,
            [result.candidate_id], result.objectives.reshape(1, -1), result, self.told, 0.0)
        summary = dict(last, final=True, stop_reason=stop_reason, told_ids=[],
                       told_objectives=np.zeros((0, len(self.task.objective_names))),
                       wall_time=time.monotonic() - self.started, structure=structure,
                       best_id=result.candidate_id, best_objectives=result.objectives,
                       best_fitness=result.fitness, best_x=result.x)
        self.publish(topics.GENERATION_SUMMARY, summary_message(self.run_id, summary))
        for publisher in self.publishers_.values():
            publisher.wait_for_all_acked(Duration(seconds=5.0))
        self.write_result(result, structure, stop_reason)
        self.get_logger().info(f'run {self.run_id} finished ({stop_reason})')
        self.finished.set_result(True)

    def write_result(self, result, structure, stop_reason):
        path = self.param('result_file')
        if not path:
            return
        with open(path, 'w', encoding='utf-8') as stream:
            json.dump({
                'run_id': self.run_id, 'task': self.task.name, 'seed': self.task.seed,
                'stop_reason': stop_reason, 'evaluations': self.told,
                'structure': list(structure),
                'best_candidate_id': result.candidate_id, 'generation': result.generation,
                'fitness': result.fitness,
                'objectives': dict(zip(self.task.objective_names, result.objectives.tolist())),
                'design': genome_spec(self.task.replace(structure=structure)).design_values(
                    result.x),
                'published': self.published,
            }, stream, indent=2)


def main(args=None):
    rclpy.init(args=args)
    node = None
    try:
        node = OptimizerNode()
        rclpy.spin_until_future_complete(node, node.finished)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except (TaskError, DispatchError, UserError) as error:
        print(f'optimizer: error: {error}', file=sys.stderr)
        return 2
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
