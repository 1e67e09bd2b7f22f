"""
The simulated rig node: runs requested trials in PyBullet as a test rig would run them.

It hears the runs (RunInfo) and candidates, and for each TrialRequest builds the candidate's
hand from its physical fields with core.rig.simulated, answers on rig/trial_status (started, start
collision or failed, then ended) and publishes the object's pose as geometry_msgs/PoseStamped
on rig/object_pose, stamped with the trial's time from its start (frame `frame_id`), at the
sample rate and with the noise and latency of its parameters.
"""

import collections
import sys
import time

from geometry_msgs.msg import PoseStamped
from hand_codesign.core import contract
from hand_codesign.core.rig.simulated import requested_trial, SampleClock, SimulatedRig
from hand_codesign.ros import topics
from hand_codesign.ros.node_main import run_node
from hand_codesign.ros.parameters import declare_read_only
from hand_codesign_msgs.msg import TrialStatus
from rclpy.node import Node
from rclpy.time import Time

PARAMETERS = {
    'rig_id': ('sim_rig', 'name of this rig in its TrialStatus messages', None),
    'rate': (0.0, 'poses per second; 0: every physics step', (0.0, 100000.0)),
    'phase': (0.0, 'offset of the sample clock, in sample periods', (0.0, 1.0)),
    'position_noise': (0.0, 'standard deviation of the position noise, m', (0.0, 1.0)),
    'angle_noise': (0.0, 'standard deviation of the orientation noise, rad', (0.0, 3.2)),
    'latency': (0.0, "seconds between a trial's start and its first poses", (0.0, 60.0)),
    'seed': (0, 'seed of the noise', (0, 2 ** 31 - 1)),
    'engine': ('', "physics engine, pybullet or mujoco; empty: the run's", None),
    'frame_id': ('world', "frame of the poses: the task's world frame", None),
    'subscribers_expected': (0, 'status and pose subscribers to await before a trial', (0, 100)),
}
MATCH_WAIT = 10.0  # s: the most a trial waits for its subscribers to match
KEPT_CANDIDATES = 4096


class SimRigNode(Node):
    """Run the trials asked for on rig/trial_requests in PyBullet."""

    def __init__(self):
        super().__init__('sim_rig')
        self.settings = declare_read_only(self, PARAMETERS)
        self.rig = SimulatedRig(SampleClock(self.settings['rate'], self.settings['phase']),
                                (self.settings['position_noise'],
                                 self.settings['angle_noise']), self.settings['seed'],
                                self.settings['engine'])
        self.runs = {}
        self.last_stamp = 0  # ns, the end of the last trial
        self.candidates = collections.OrderedDict()
        self.status, self.poses = (self.create_publisher(
            topics.MESSAGE_TYPES[name], name, topics.QOS[name])
            for name in (contract.TRIAL_STATUS, contract.OBJECT_POSE))
        for name, callback in ((contract.RUN_INFO, self.on_run_info),
                               (contract.CANDIDATES, self.on_candidate),
                               (contract.TRIAL_REQUESTS, self.on_request)):
            self.create_subscription(topics.MESSAGE_TYPES[name], name, callback,
                                     topics.QOS[name])
        self.get_logger().info(f'simulated rig {self.settings["rig_id"]} ready')

    def on_run_info(self, message):
        self.runs[message.run_id] = message

    def on_candidate(self, message):
        self.candidates[(message.run_id, message.candidate_id, message.attempt)] = message
        while len(self.candidates) > KEPT_CANDIDATES:
            self.candidates.popitem(last=False)

    def on_request(self, request):
        candidate = self.candidates.get((request.run_id, request.candidate_id,
                                         request.attempt))
        run = self.runs.get(request.run_id)
        try:
            if candidate is None or run is None:
                raise ValueError(f'no {"Candidate" if run else "RunInfo"} heard for trial '
                                 f'{request.trial_id} of candidate {request.candidate_id}')
            task, design, spec = requested_trial(run, candidate, request)
        except ValueError as error:
            self.report(request, contract.TRIAL_FAILED, self.now(), str(error))
            return
        self.wait_for_subscribers()
        start = self.now()
        poses = []
        outcome = self.rig.run(task, design, spec,
                               lambda t, p, q: poses.append(self.pose(start, t, p, q)))
        if outcome == 'collision':
            self.report(request, contract.TRIAL_START_COLLISION, start)
            return
        self.report(request, contract.TRIAL_STARTED, start)
        time.sleep(self.settings['latency'])
        for pose in poses:
            self.poses.publish(pose)
        end = poses[-1].header.stamp if poses else start
        self.last_stamp = Time.from_msg(end).nanoseconds
        self.report(request, contract.TRIAL_ENDED, end,
                    'the simulation became unstable' if outcome == 'unstable' else '')

    def wait_for_subscribers(self):
        # status and poses are volatile: what is sent before a recorder matches is not recorded
        deadline, wanted = time.monotonic() + MATCH_WAIT, self.settings['subscribers_expected']
        while time.monotonic() < deadline and min(
                p.get_subscription_count() for p in (self.status, self.poses)) < wanted:
            time.sleep(0.01)

    def now(self):
        # simulated trials run faster than real time and are stamped in simulated time: the
        # rig's clock never goes back, so the stamps of two trials never overlap
        now = max(self.get_clock().now().nanoseconds, self.last_stamp + 1_000_000)
        return Time(nanoseconds=now).to_msg()

    def pose(self, start, seconds, position, orientation):
        message = PoseStamped()
        stamp = Time.from_msg(start).nanoseconds + round(seconds * 1e9)
        message.header.stamp = Time(nanoseconds=stamp).to_msg()
        message.header.frame_id = self.settings['frame_id']
        point, turn = message.pose.position, message.pose.orientation
        point.x, point.y, point.z = (float(v) for v in position)
        turn.x, turn.y, turn.z, turn.w = (float(v) for v in orientation)
        return message

    def report(self, request, event, stamp, reason=''):
        self.status.publish(TrialStatus(
            rig_id=self.settings['rig_id'], trial_id=request.trial_id,
            evaluator_id=request.evaluator_id, event=event, stamp=stamp, reason=reason))

    def destroy_node(self):
        self.rig.close()
        super().destroy_node()


def main(args=None):
    return run_node(SimRigNode, 'sim_rig', args)


if __name__ == '__main__':
    sys.exit(main())
