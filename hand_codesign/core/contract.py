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


def type_name(message):
    """Return the ROS type name of a message of this package, e.g. 'hand_codesign_msgs/msg/X'."""
    return f'{MESSAGES_PACKAGE}/msg/{message}'


RUN_INFO_TYPE = type_name('RunInfo')
CANDIDATE_TYPE = type_name('Candidate')
EVALUATION_TYPE = type_name('Evaluation')
EVALUATOR_STATUS_TYPE = type_name('EvaluatorStatus')
GENERATION_SUMMARY_TYPE = type_name('GenerationSummary')

# topic -> ROS type name, in the order the recorder subscribes
TOPIC_TYPES = {
    RUN_INFO: RUN_INFO_TYPE,
    CANDIDATES: CANDIDATE_TYPE,
    EVALUATIONS: EVALUATION_TYPE,
    EVALUATOR_STATUS: EVALUATOR_STATUS_TYPE,
    GENERATION_SUMMARY: GENERATION_SUMMARY_TYPE,
}
LOOP_TYPES = tuple(TOPIC_TYPES.values())

# Evaluation.status (the constants of Evaluation.msg)
STATUS_OK = 0
STATUS_REJECTED = 1
STATUS_NAMES = {STATUS_OK: 'ok', STATUS_REJECTED: 'rejected'}

# The recorder logs a line starting with this once its subscriptions exist; a runner waits
# for it before starting the optimizer.
RECORDER_READY = 'recorder ready'

# The optimizer logs this line once its evaluators are there and the run starts; the runner's
# supervision waits for it (its start deadline).
EVALUATORS_READY = 'evaluators ready, starting'
