"""The Fast DDS profile the processes of a run start with (hand_codesign.ros.discovery)."""

import subprocess
import sys

from hand_codesign.ros.discovery import PROFILE_VARIABLES
from hand_codesign.ros.discovery import START_PROFILE
from hand_codesign.ros.discovery import start_profile
from hand_codesign.ros.runner import System
import pytest

BARE_NODE = ('import rclpy; rclpy.init(); node = rclpy.create_node("profiled"); '
             'node.destroy_node(); rclpy.shutdown()')


@pytest.mark.system
def test_a_process_of_a_run_loads_the_start_profile_without_complaint(tmp_path):
    environment = System(tmp_path / 'bag', domain_id=99).environment
    assert environment[PROFILE_VARIABLES[0]] == str(START_PROFILE)
    started = subprocess.run([sys.executable, '-c', BARE_NODE], env=environment,
                             capture_output=True, text=True, timeout=60)
    # Fast DDS says what it cannot parse on standard error, and carries on without it
    assert started.returncode == 0 and started.stderr == '', started.stderr


def test_the_users_own_profile_stands():
    for variable in PROFILE_VARIABLES:
        assert start_profile({variable: '/home/me/dds.xml'}) == {}
    assert start_profile(dict.fromkeys(PROFILE_VARIABLES, '')) == {
        PROFILE_VARIABLES[0]: str(START_PROFILE)}
