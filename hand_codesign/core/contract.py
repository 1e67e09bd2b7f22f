"""
The message contract of the co-design loop, spelled once: topics, their types, status codes.

Every process of a run and every reader of its bag agrees on these names; this module holds
them as plain strings and numbers, so that the analysis (which reads bags without ROS), the
nodes and the tests import one definition. `hand_codesign.ros.topics` adds the message
classes and QoS on top; the .msg files in msg_defs/ define the same status constants, and a
test checks that both agree.
"""

MESSAGES_PACKAGE = 'hand_codesign_msgs'

# Relative topic names of the loop.
RUN_INFO = 'run_info'
CANDIDATES = 'candidates'
EVALUATIONS = 'evaluations'
EVALUATOR_STATUS = 'evaluator_status'
GENERATION_SUMMARY = 'generation_summary'
# Hardware in the loop (hand_codesign.core.rig.trials): a rig evaluator's trial requests, the rig's
# trial events and the object's measured pose.
TRIAL_REQUESTS = 'rig/trial_requests'
TRIAL_STATUS = 'rig/trial_status'
OBJECT_POSE = 'rig/object_pose'


def type_name(message):
    """Return the ROS type name of a message of this package, e.g. 'hand_codesign_msgs/msg/X'."""
    return f'{MESSAGES_PACKAGE}/msg/{message}'


RUN_INFO_TYPE = type_name('RunInfo')
CANDIDATE_TYPE = type_name('Candidate')
EVALUATION_TYPE = type_name('Evaluation')
EVALUATOR_STATUS_TYPE = type_name('EvaluatorStatus')
GENERATION_SUMMARY_TYPE = type_name('GenerationSummary')
TRIAL_REQUEST_TYPE = type_name('TrialRequest')
TRIAL_STATUS_TYPE = type_name('TrialStatus')
POSE_STAMPED_TYPE = 'geometry_msgs/msg/PoseStamped'

# topic -> ROS type name of the loop itself
LOOP_TOPIC_TYPES = {
    RUN_INFO: RUN_INFO_TYPE,
    CANDIDATES: CANDIDATE_TYPE,
    EVALUATIONS: EVALUATION_TYPE,
    EVALUATOR_STATUS: EVALUATOR_STATUS_TYPE,
    GENERATION_SUMMARY: GENERATION_SUMMARY_TYPE,
}
LOOP_TYPES = tuple(LOOP_TOPIC_TYPES.values())
# the trials of rig evaluators: recorded, so the bag holds each measured pose trace
RIG_TOPIC_TYPES = {
    TRIAL_REQUESTS: TRIAL_REQUEST_TYPE,
    TRIAL_STATUS: TRIAL_STATUS_TYPE,
    OBJECT_POSE: POSE_STAMPED_TYPE,
}
# every topic, in the order the recorder subscribes
TOPIC_TYPES = {**LOOP_TOPIC_TYPES, **RIG_TOPIC_TYPES}

# What a 3D viewer (Foxglove, Lichtblick, RViz) draws: standard messages beside the loop's,
# recorded in the bag too. With each generation summary the optimizer publishes the best
# design so far (core.sim.geometry's shapes) as markers in the frame WORLD_FRAME.
BEST_DESIGN = 'best_design'
MARKER_ARRAY_TYPE = 'visualization_msgs/msg/MarkerArray'
WORLD_FRAME = 'world'
# The best design as a robot model (ros.robot_view_node): its URDF on ROBOT_DESCRIPTION
# (latched, again on each new best design), the palm fixed in WORLD_FRAME on TF_STATIC and
# every joint's transform, frame by frame over its rollout in world 0, on TF: what RViz's
# RobotModel and Foxglove's URDF layer need, with no robot_state_publisher.
ROBOT_DESCRIPTION = 'robot_description'
TF = 'tf'
TF_STATIC = 'tf_static'
STRING_TYPE = 'std_msgs/msg/String'
TF_MESSAGE_TYPE = 'tf2_msgs/msg/TFMessage'
ROBOT_TOPIC_TYPES = {ROBOT_DESCRIPTION: STRING_TYPE, TF_STATIC: TF_MESSAGE_TYPE,
                     TF: TF_MESSAGE_TYPE}
VIEW_TOPIC_TYPES = {BEST_DESIGN: MARKER_ARRAY_TYPE, **ROBOT_TOPIC_TYPES}
# every topic a run's recorder writes to its bag (and a live view forwards)
RECORDED_TOPIC_TYPES = {**TOPIC_TYPES, **VIEW_TOPIC_TYPES}

# The topics of a rollout written by `hand-codesign replay BAG --mcap FILE`: per frame, the
# hand and the object as markers, and the goal in effect (the next one, then the last one).
REPLAY_MARKERS = 'replay/markers'
REPLAY_GOAL = 'replay/goal_pose'
POSE_STAMPED_TYPE = 'geometry_msgs/msg/PoseStamped'
# With them, the hand as a robot model (ROBOT_TOPIC_TYPES): its URDF and the palm once, at the
# start, and the joints' transforms at every frame.
REPLAY_TOPIC_TYPES = {REPLAY_MARKERS: MARKER_ARRAY_TYPE, REPLAY_GOAL: POSE_STAMPED_TYPE,
                      **ROBOT_TOPIC_TYPES}

# Evaluation.status (the constants of Evaluation.msg)
STATUS_OK = 0
STATUS_REJECTED = 1
STATUS_NAMES = {STATUS_OK: 'ok', STATUS_REJECTED: 'rejected'}

# TrialStatus.event (the constants of TrialStatus.msg)
TRIAL_STARTED = 0
TRIAL_ENDED = 1
TRIAL_START_COLLISION = 2
TRIAL_FAILED = 3

# The recorder logs a line starting with this once its subscriptions exist; a runner waits
# for it before starting the optimizer.
RECORDER_READY = 'recorder ready'
# The robot view logs this once it listens; a runner starts the optimizer only then, so the
# robot view hears the run's final best design even when the run is short.
ROBOT_VIEW_READY = 'robot view ready'
# The live view (`hand-codesign run --live`) logs this, then ': ws://HOST:PORT', once it serves.
LIVE_READY = 'live view ready'

# The optimizer logs this line once its evaluators are there and the run starts; the runner's
# supervision waits for it (its start deadline).
EVALUATORS_READY = 'evaluators ready, starting'
