"""
Disturb a run: publish a foreign run and malformed candidates into the run's ROS domain.

Started by test_system.py before the run; waits for the run's RunInfo, then publishes a
RunInfo and a Candidate of a foreign run, a Candidate of the run with a genome of the wrong
length, one with NaN values, one of an impossible structure, and an Evaluation of the foreign
run; it leaves once the malformed candidates are answered.
"""

import sys
import time

from hand_codesign.ros import topics
from hand_codesign_msgs.msg import Candidate
from hand_codesign_msgs.msg import Evaluation
from hand_codesign_msgs.msg import RunInfo
import rclpy


def main():
    rclpy.init()
    node = rclpy.create_node('intruder')
    runs = []
    node.create_subscription(RunInfo, topics.RUN_INFO, runs.append, topics.QOS[topics.RUN_INFO])
    answered = set()
    node.create_subscription(Evaluation, topics.EVALUATIONS,
                             lambda message: answered.add(message.candidate_id),
                             topics.QOS[topics.EVALUATIONS])
    publishers = {name: node.create_publisher(topics.MESSAGE_TYPES[name], name,
                                              topics.QOS[name])
                  for name in (topics.RUN_INFO, topics.CANDIDATES, topics.EVALUATIONS)}
    deadline = time.monotonic() + 90
    while not runs and time.monotonic() < deadline:
        rclpy.spin_once(node, timeout_sec=0.1)
    if not runs:
        print('no RunInfo seen', file=sys.stderr)
        return 1
    run_id = runs[0].run_id
    size = len(runs[0].objective_names)
    publishers[topics.RUN_INFO].publish(RunInfo(run_id='foreign-run', task_yaml='not: a task'))
    publishers[topics.CANDIDATES].publish(Candidate(
        run_id='foreign-run', candidate_id=0, genome=[0.5] * 10, structure=[2, 2]))
    publishers[topics.CANDIDATES].publish(Candidate(
        run_id=run_id, candidate_id=10**9, genome=[0.5], structure=[2, 2]))
    publishers[topics.CANDIDATES].publish(Candidate(
        run_id=run_id, candidate_id=10**9 + 1, genome=[float('nan')] * 24, structure=[2, 2]))
    publishers[topics.CANDIDATES].publish(Candidate(
        run_id=run_id, candidate_id=10**9 + 2, genome=[0.5] * 24, structure=[0, 7]))
    publishers[topics.EVALUATIONS].publish(Evaluation(
        run_id='foreign-run', candidate_id=0, objectives=[0.0] * size, evaluator_id='intruder'))
    for publisher in publishers.values():
        publisher.wait_for_all_acked()
    # stay until an evaluator has answered each malformed candidate of the run
    malformed = {10**9, 10**9 + 1, 10**9 + 2}
    deadline = time.monotonic() + 60
    while malformed - answered and time.monotonic() < deadline:
        rclpy.spin_once(node, timeout_sec=0.1)
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
