"""
Message classes and QoS of the co-design loop's topics, shared by every node.

The names, type names and status codes are spelled once, without ROS, in
hand_codesign.core.contract; this module adds what needs rclpy and the generated messages.

Every topic of the loop is reliable and transient-local with a deep history, so that no
candidate or evaluation is lost when a population is larger than a default depth, and a
subscriber that matches late (a recorder, an evaluator started by hand) still receives what
was published before it matched.
"""

import time

from geometry_msgs.msg import PoseStamped
from hand_codesign.core.contract import BEST_DESIGN
from hand_codesign.core.contract import CANDIDATES
from hand_codesign.core.contract import EVALUATIONS
from hand_codesign.core.contract import EVALUATOR_STATUS
from hand_codesign.core.contract import GENERATION_SUMMARY
from hand_codesign.core.contract import OBJECT_POSE
from hand_codesign.core.contract import ROBOT_DESCRIPTION
from hand_codesign.core.contract import RUN_INFO
from hand_codesign.core.contract import TF
from hand_codesign.core.contract import TF_STATIC
from hand_codesign.core.contract import TRIAL_REQUESTS
from hand_codesign.core.contract import TRIAL_STATUS
from hand_codesign_msgs.msg import Candidate
from hand_codesign_msgs.msg import Evaluation
from hand_codesign_msgs.msg import EvaluatorStatus
from hand_codesign_msgs.msg import GenerationSummary
from hand_codesign_msgs.msg import RunInfo
from hand_codesign_msgs.msg import TrialRequest
from hand_codesign_msgs.msg import TrialStatus
from rclpy.duration import Duration
from rclpy.qos import DurabilityPolicy
from rclpy.qos import HistoryPolicy
from rclpy.qos import QoSProfile
from rclpy.qos import ReliabilityPolicy
from std_msgs.msg import String
from tf2_msgs.msg import TFMessage
from visualization_msgs.msg import MarkerArray

# Deep enough for several generations of the largest population of Table I (250).
HISTORY_DEPTH = 4096

LOOP_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=HISTORY_DEPTH,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)

# Heartbeats are only worth their latest value; a late joiner needs none of the old ones.
STATUS_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=64,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)

# A rig's trials: every pose of a trace matters (the evaluator scores it) and none is worth
# anything after its trial, so the history is deep and nothing is kept for late joiners.
RIG_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=HISTORY_DEPTH,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)

# The robot model, as robot_state_publisher and tf2 offer it: the description and the static
# transforms latched (only the last one matters), the moving transforms a plain stream.
LATCHED_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)
TF_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=100,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)

MESSAGE_TYPES = {
    RUN_INFO: RunInfo,
    CANDIDATES: Candidate,
    EVALUATIONS: Evaluation,
    EVALUATOR_STATUS: EvaluatorStatus,
    GENERATION_SUMMARY: GenerationSummary,
    TRIAL_REQUESTS: TrialRequest,
    TRIAL_STATUS: TrialStatus,
    OBJECT_POSE: PoseStamped,
}

# What a 3D viewer draws (core.contract.VIEW_TOPIC_TYPES), and every topic a bag records.
VIEW_MESSAGE_TYPES = {BEST_DESIGN: MarkerArray, ROBOT_DESCRIPTION: String,
                      TF_STATIC: TFMessage, TF: TFMessage}
RECORDED_MESSAGE_TYPES = {**MESSAGE_TYPES, **VIEW_MESSAGE_TYPES}
# what the optimizer node publishes
OPTIMIZER_TOPICS = (RUN_INFO, CANDIDATES, GENERATION_SUMMARY, BEST_DESIGN)

QOS = {
    RUN_INFO: LOOP_QOS,
    CANDIDATES: LOOP_QOS,
    EVALUATIONS: LOOP_QOS,
    EVALUATOR_STATUS: STATUS_QOS,
    GENERATION_SUMMARY: LOOP_QOS,
    # one per summary, like the summaries: a late viewer or recorder gets them all
    BEST_DESIGN: LOOP_QOS,
    ROBOT_DESCRIPTION: LATCHED_QOS,
    TF_STATIC: LATCHED_QOS,
    TF: TF_QOS,
    TRIAL_REQUESTS: RIG_QOS,
    TRIAL_STATUS: RIG_QOS,
    OBJECT_POSE: RIG_QOS,
}


def type_name(message_class):
    """Return the ROS type name of a message class, e.g. 'hand_codesign_msgs/msg/Candidate'."""
    module = message_class.__module__.split('.')[0]
    return f'{module}/msg/{message_class.__name__}'


# How long a publisher that is done waits for its expected subscribers (a recorder being
# restarted by the runner) before it gives its messages up, and for their acknowledgements.
RETURN_WAIT = 30.0
ACK_WAIT = 5.0


def deliver(publishers, subscribers_expected, timeout=RETURN_WAIT):
    """
    Return once every publisher's expected subscribers are there and acknowledged everything.

    The history of a publisher ends with its process: a recorder restarted after it died
    (ros.runner, bag.recovery) gets the messages it missed only from publishers that still
    exist, so a node that is done waits for it (at most timeout s) before it exits.
    """
    deadline = time.monotonic() + timeout
    for publisher in publishers:
        while (publisher.get_subscription_count() < subscribers_expected
               and time.monotonic() < deadline):
            time.sleep(0.05)
    # one deadline for all: a subscriber killed a moment ago is still matched and never
    # acknowledges anything until its lease runs out
    deadline = time.monotonic() + ACK_WAIT
    for publisher in publishers:
        left = max(0.0, deadline - time.monotonic())
        publisher.wait_for_all_acked(Duration(nanoseconds=int(left * 1e9)))
