"""
A co-design run as ROS 2 users start one: `ros2 launch hand_codesign codesign.launch.py`.

    ros2 launch hand_codesign codesign.launch.py task_file:=config/tasks/task5.yaml \
        evaluators:=2 bag:=bags/run1 seed:=1

Starts the recorder (it writes the bag), `evaluators` evaluators (evaluator-0, evaluator-1, ...,
as a run's own, each node named after its id: /evaluator_0, ...) and the optimizer, each with
its parameter file from this package's share/config; when the optimizer ends, the launch stops
the others and the recorder closes the bag. The processes are those of `hand-codesign run`,
which adds what a launch file does not: restarting a dead evaluator or recorder, and a free ROS
domain on request. This launch runs on the shell's ROS_DOMAIN_ID, so `ros2 topic echo
/generation_summary` there follows the run.

The launch arguments:
    task_file   task file (YAML); a relative path is looked for in the working folder, then in
                this package's share/ (default config/tasks/task5.yaml)
    evaluators  evaluator processes on this host (default 2; 0: only evaluators started
                elsewhere, the optimizer then waits for one)
    bag         bag folder to write, a new one (default bags/launch-<date>-<time>)
    seed        run seed (default -1: the task file's)
"""

import os
import time

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.actions import EmitEvent
from launch.actions import OpaqueFunction
from launch.actions import RegisterEventHandler
from launch.event_handlers import OnProcessExit
from launch.events import Shutdown
from launch_ros.actions import Node

PACKAGE = 'hand_codesign'
ARGUMENTS = {  # name: (default, description)
    'task_file': ('config/tasks/task5.yaml', 'task file (YAML); relative: here, else share/'),
    'evaluators': ('2', 'evaluator processes to start on this host'),
    'bag': ('', 'bag folder to write (new); empty: bags/launch-<date>-<time>'),
    'seed': ('-1', "run seed; -1: the task file's"),
}


def parameter_file(name):
    """Return the path of a node's parameter file in the package's share/config."""
    return os.path.join(get_package_share_directory(PACKAGE), 'config', name)


def run_nodes(context):
    """Return the recorder, evaluators and optimizer for the launch arguments given."""
    given = {name: context.launch_configurations[name] for name in ARGUMENTS}
    evaluators = int(given['evaluators'])
    bag = given['bag'] or time.strftime('bags/launch-%Y%m%d-%H%M%S')
    recorder = Node(package=PACKAGE, executable='recorder', output='screen',
                    parameters=[parameter_file('recorder.yaml'), {'bag_path': bag}])
    # no node name given: each evaluator takes the one of its id (/evaluator_0, ...)
    pool = [Node(package=PACKAGE, executable='evaluator', output='screen',
                 parameters=[parameter_file('evaluator.yaml'), {
                     'evaluator_id': f'evaluator-{index}',
                     'subscribers_expected': 2}])  # the optimizer and the recorder
            for index in range(evaluators)]
    optimizer = Node(package=PACKAGE, executable='optimizer', output='screen',
                     parameters=[parameter_file('optimizer.yaml'), {
                         'task_file': given['task_file'],
                         'seed': int(given['seed']),
                         'evaluators_expected': max(evaluators, 1),
                         'subscribers_expected': 1,  # the recorder
                         'result_file': os.path.join(bag, 'result.json')}])
    # the run is over when the optimizer ends: stop the others (the recorder closes the bag)
    finished = RegisterEventHandler(OnProcessExit(
        target_action=optimizer,
        on_exit=[EmitEvent(event=Shutdown(reason='the optimizer finished'))]))
    return [recorder, *pool, optimizer, finished]


def generate_launch_description():
    """Return the launch description: its arguments, then the nodes of the run."""
    return LaunchDescription(
        [DeclareLaunchArgument(name, default_value=default, description=description)
         for name, (default, description) in ARGUMENTS.items()]
        + [OpaqueFunction(function=run_nodes)])
