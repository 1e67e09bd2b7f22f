"""The message contract spelled without ROS agrees with the messages and topics the nodes use."""

from hand_codesign.core import contract
from hand_codesign.ros import topics
from hand_codesign_msgs.msg import Evaluation
from hand_codesign_msgs.msg import TrialStatus
import pytest


def test_every_topic_has_the_type_of_its_message_class():
    assert list(contract.TOPIC_TYPES) == list(topics.MESSAGE_TYPES)
    assert list(contract.RECORDED_TOPIC_TYPES) == list(topics.RECORDED_MESSAGE_TYPES)
    for topic, message_class in topics.RECORDED_MESSAGE_TYPES.items():
        assert contract.RECORDED_TOPIC_TYPES[topic] == topics.type_name(message_class)
    assert set(topics.QOS) == set(contract.RECORDED_TOPIC_TYPES)
    # the bag reader decodes the loop's own types; the rig's and the view's are read apart
    assert set(contract.LOOP_TYPES) == set(contract.LOOP_TOPIC_TYPES.values())
    assert all(name.startswith(contract.MESSAGES_PACKAGE + '/') for name in contract.LOOP_TYPES)


def test_status_codes_are_those_of_evaluation_msg():
    assert contract.STATUS_OK == Evaluation.STATUS_OK
    assert contract.STATUS_REJECTED == Evaluation.STATUS_REJECTED
    assert contract.STATUS_NAMES == {Evaluation.STATUS_OK: 'ok', Evaluation.STATUS_REJECTED:
                                     'rejected'}


def test_trial_events_are_those_of_trial_status_msg():
    assert (contract.TRIAL_STARTED, contract.TRIAL_ENDED, contract.TRIAL_START_COLLISION,
            contract.TRIAL_FAILED) == (TrialStatus.EVENT_STARTED, TrialStatus.EVENT_ENDED,
                                       TrialStatus.EVENT_START_COLLISION,
                                       TrialStatus.EVENT_FAILED)
    assert set(contract.LOOP_TOPIC_TYPES) | set(contract.RIG_TOPIC_TYPES) == set(
        contract.TOPIC_TYPES)


@pytest.mark.system
def test_the_contract_module_loads_neither_rclpy_nor_the_messages():
    import subprocess
    import sys
    code = ('import sys; import hand_codesign.core.contract; '
            'print(sorted(m for m in sys.modules if m.startswith(("rclpy", "hand_codesign_msgs"'
            '))))')
    output = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                            check=True).stdout
    assert output.strip() == '[]'
