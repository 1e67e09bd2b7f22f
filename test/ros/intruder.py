"""
Disturb a run as a process without a key on the run's ROS domain would.

Started by test_system.py before the run; waits for the run's RunInfo, then publishes a
RunInfo and a Candidate of a foreign run, an unsigned RunInfo of the run itself announcing
another task, unsigned Candidates of the run (a genome of the wrong length, NaN values, an
impossible structure) addressed to the run's evaluators, and an Evaluation of the foreign run.
Then it forges: it answers every Candidate at once with objectives of 0 in the name of the
evaluator the optimizer addressed, publishes FORGED_SUMMARIES GenerationSummaries of the run
claiming objectives of 0, and beats heartbeats for an evaluator that does not exist and in
the name of one that does, asking for much work, until the run's final GenerationSummary. It
prints how many evaluations it forged.
"""

import sys
import time

from hand_codesign.ros import topics
from hand_codesign_msgs.msg import Candidate
from hand_codesign_msgs.msg import Evaluation
from hand_codesign_msgs.msg import EvaluatorStatus
from hand_codesign_msgs.msg import GenerationSummary
from hand_codesign_msgs.msg import RunInfo
import rclpy

FORGED_SUMMARIES = 6
MALFORMED = {10**9: ([0.5], [2, 2]), 10**9 + 1: ([float('nan')] * 24, [2, 2]),
             10**9 + 2: ([0.5] * 24, [0, 7])}


def main():
    rclpy.init()
    node = rclpy.create_node('intruder')
    runs, finals = [], []
    node.create_subscription(RunInfo, topics.RUN_INFO, runs.append, topics.QOS[topics.RUN_INFO])
    node.create_subscription(GenerationSummary, topics.GENERATION_SUMMARY,
                             lambda message: message.final and finals.append(message),
                             topics.QOS[topics.GENERATION_SUMMARY])
    publishers = {name: node.create_publisher(topics.MESSAGE_TYPES[name], name,
                                              topics.QOS[name])
                  for name in (topics.RUN_INFO, topics.CANDIDATES, topics.EVALUATIONS,
                               topics.GENERATION_SUMMARY, topics.EVALUATOR_STATUS)}
    forged, early = [], []

    def forge(candidate):
        if not runs:   # the history of candidates may arrive before the RunInfo
            early.append(candidate)
            return
        if candidate.run_id == runs[0].run_id and candidate.candidate_id < 10**9:
            forged.append(candidate.candidate_id)
            publishers[topics.EVALUATIONS].publish(Evaluation(
                run_id=candidate.run_id, generation=candidate.generation,
                candidate_id=candidate.candidate_id, attempt=candidate.attempt,
                evaluator_id=candidate.evaluator_id, status=Evaluation.STATUS_OK,
                objectives=[0.0] * len(runs[0].objective_names),
                objective_names=list(runs[0].objective_names), signature=[0] * 32))

    node.create_subscription(Candidate, topics.CANDIDATES, forge, topics.QOS[topics.CANDIDATES])
    deadline = time.monotonic() + 90
    while not runs and time.monotonic() < deadline:
        rclpy.spin_once(node, timeout_sec=0.1)
    if not runs:
        print('no RunInfo seen', file=sys.stderr)
        return 1
    run = runs[0]
    for candidate in early:
        forge(candidate)
    publishers[topics.RUN_INFO].publish(RunInfo(run_id='foreign-run', task_yaml='not: a task'))
    publishers[topics.RUN_INFO].publish(RunInfo(
        run_id=run.run_id, task_name=run.task_name, task_yaml='not: the run task',
        seed=run.seed, objective_names=run.objective_names))
    publishers[topics.CANDIDATES].publish(Candidate(
        run_id='foreign-run', candidate_id=0, genome=[0.5] * 10, structure=[2, 2]))
    for evaluator_id in ('', 'evaluator-0', 'evaluator-1'):
        for candidate_id, (genome, structure) in MALFORMED.items():
            publishers[topics.CANDIDATES].publish(Candidate(
                run_id=run.run_id, candidate_id=candidate_id, genome=genome,
                structure=structure, evaluator_id=evaluator_id))
    publishers[topics.EVALUATIONS].publish(Evaluation(
        run_id='foreign-run', candidate_id=0, objectives=[0.0], evaluator_id='intruder'))
    for generation in range(100, 100 + FORGED_SUMMARIES):
        publishers[topics.GENERATION_SUMMARY].publish(GenerationSummary(
            run_id=run.run_id, generation=generation, objective_names=run.objective_names,
            best=[0.0] * len(run.objective_names), best_fitness=0.0, wall_time=1.0,
            best_objectives=[0.0] * len(run.objective_names), signature=[0] * 64))
    deadline = time.monotonic() + 180
    while not finals and time.monotonic() < deadline:
        for evaluator_id in ('phantom', 'evaluator-0'):   # nobody, and somebody else
            publishers[topics.EVALUATOR_STATUS].publish(EvaluatorStatus(
                evaluator_id=evaluator_id, run_id=run.run_id, capacity=100, load=0,
                signature=[0] * 32))
        rclpy.spin_once(node, timeout_sec=0.1)
    print(f'forged {len(forged)} evaluations')
    node.destroy_node()
    rclpy.try_shutdown()
    return 0 if finals else 1


if __name__ == '__main__':
    sys.exit(main())
