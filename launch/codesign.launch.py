"""
A co-design run as ROS 2 users start one: `ros2 launch hand_codesign codesign.launch.py`.

    ros2 launch hand_codesign codesign.launch.py task_file:=config/tasks/task5.yaml \
        evaluators:=2 bag:=bags/run1 seed:=1 population:=16 world_states:=16 live:=true

Starts the recorder (it writes the bag), `evaluators` evaluators (evaluator-0, evaluator-1, ...,
as a run's own, each node named after its id: /evaluator_0, ...) and the optimizer, each with
its parameter file from this package's share/config, then `params_file` if given, then the
launch arguments given, and the robot view (the best design as robot_description and /tf for
RViz and Foxglove); with `live:=true` also the live view for Foxglove. When the optimizer ends
and the robot view has played the final best design, the launch stops the others and the
recorder closes the bag. The processes are those of
`hand-codesign run`, which adds what a launch file does not: restarting a dead evaluator or
recorder, and a free ROS domain on request. This launch runs on the shell's ROS_DOMAIN_ID, so
`ros2 topic echo /generation_summary` there follows the run.

The launch arguments (`ros2 launch hand_codesign codesign.launch.py --show-args` lists them):
    task_file     task file (YAML); a relative path is looked for in the working folder, then
                  in this package's share/ (default config/tasks/task5.yaml)
    evaluators    evaluator processes on this host (default 2; 0: only evaluators started
                  elsewhere, the optimizer then waits for one)
    bag           bag folder to write, a new one (default bags/launch-<date>-<time>)
    seed          run seed (default -1: the task file's)
    engine        physics engine, pybullet or mujoco (default empty: the task file's)
    iterations    generations (default 0: the task file's)
    population    candidates per generation (default 0: the task file's)
    world_states  randomized worlds per candidate (default 0: the task file's)
    params_file   a ROS 2 parameter file for every node (`/**:` or node names as keys), read
                  after the package's own files; a launch argument given wins over it
    live          true: serve the run to Foxglove over WebSocket (default false)
    live_port     the live view's TCP port on 127.0.0.1 (default 8765; 0: any free one)
"""

import os
import time

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.actions import EmitEvent
from launch.actions import OpaqueFunction
from launch.actions import RegisterEventHandler
from launch.actions import TimerAction
from launch.event_handlers import OnProcessExit
from launch.events import Shutdown
from launch_ros.actions import Node

PACKAGE = 'hand_codesign'
ARGUMENTS = {  # name: (default, description)
    'task_file': ('config/tasks/task5.yaml', 'task file (YAML); relative: here, else share/'),
    'evaluators': ('2', 'evaluator processes to start on this host'),
    'bag': ('', 'bag folder to write (new); empty: bags/launch-<date>-<time>'),
    'seed': ('-1', "run seed; -1: the task file's"),
    'engine': ('', "physics engine, pybullet or mujoco; empty: the task file's"),
    'iterations': ('0', "generations; 0: the task file's"),
    'population': ('0', "candidates per generation; 0: the task file's"),
    'world_states': ('0', "randomized worlds per candidate; 0: the task file's"),
    'params_file': ('', "parameter file for every node, after the package's; empty: none"),
    'live': ('false', 'true: serve the run live to Foxglove (WebSocket on 127.0.0.1)'),
    'live_port': ('8765', "the live view's TCP port; 0: any free one"),
}
# launch argument -> the optimizer parameter it sets when given other than its default
OPTIMIZER_ARGUMENTS = ('task_file', 'seed', 'engine', 'iterations', 'population', 'world_states')
ROBOT_VIEW_WAIT = 30.0  # s, as ros.runner's
WHOLE_NUMBERS = {'evaluators': 0, 'seed': -1, 'iterations': 0, 'population': 0,
                 'world_states': 0, 'live_port': 0}   # name: the least value


def parameter_file(name):
    """Return the path of a node's parameter file in the package's share/config."""
    return os.path.join(get_package_share_directory(PACKAGE), 'config', name)


def checked(given):
    """Return the launch arguments with numbers as int; ValueError in one line if one is bad."""
    values = dict(given)
    for name, least in WHOLE_NUMBERS.items():
        text = given[name].strip()
        if not text.lstrip('-').isdigit() or int(text) < least:
            raise ValueError(f'launch argument {name}: expected a whole number >= {least}, '
                             f'got "{given[name]}"')
        values[name] = int(text)
    if given['engine'] not in ('', 'pybullet', 'mujoco'):
        raise ValueError(f'launch argument engine: expected pybullet or mujoco, got '
                         f'"{given["engine"]}"')
    if given['live'].lower() not in ('true', 'false'):
        raise ValueError(f'launch argument live: expected true or false, got "{given["live"]}"')
    if given['params_file'] and not os.path.isfile(given['params_file']):
        raise ValueError(f'launch argument params_file: no such file "{given["params_file"]}"')
    values['live'] = given['live'].lower() == 'true'
    return values


def files(executable, given):
    """Return a node's parameter files: the package's, then the user's params_file if any."""
    return [parameter_file(f'{executable}.yaml')] + (
        [given['params_file']] if given['params_file'] else [])


def run_nodes(context):
    """Return the recorder, evaluators, optimizer (and live view) for the launch arguments."""
    given = checked({name: context.launch_configurations[name] for name in ARGUMENTS})
    evaluators = given['evaluators']
    bag = given['bag'] or time.strftime('bags/launch-%Y%m%d-%H%M%S')
    recorder = Node(package=PACKAGE, executable='recorder', output='screen',
                    parameters=[*files('recorder', given), {'bag_path': bag}])
    # no node name given: each evaluator takes the one of its id (/evaluator_0, ...)
    pool = [Node(package=PACKAGE, executable='evaluator', output='screen',
                 parameters=[*files('evaluator', given), {
                     'evaluator_id': f'evaluator-{index}',
                     'subscribers_expected': 2}])  # the optimizer and the recorder
            for index in range(evaluators)]
    # a launch argument left at its default keeps what the parameter files say
    chosen = {name: given[name] for name in OPTIMIZER_ARGUMENTS
              if str(given[name]) != ARGUMENTS[name][0]}
    optimizer = Node(package=PACKAGE, executable='optimizer', output='screen',
                     parameters=[*files('optimizer', given), {
                         'evaluators_expected': max(evaluators, 1),
                         'subscribers_expected': 1,  # the recorder
                         'result_file': os.path.join(bag, 'result.json'),
                         **chosen}])
    live = [Node(package=PACKAGE, executable='live_view', output='screen',
                 parameters=[{'port': given['live_port']}])] if given['live'] else []
    robot_view = Node(package=PACKAGE, executable='robot_view', output='screen',
                      parameters=files('robot_view', given))
    # the run is over when the optimizer ends and the robot view has played the final best
    # design's rollout into the bag (at most ROBOT_VIEW_WAIT s later): stop the others then
    # (the recorder closes the bag)
    finished = RegisterEventHandler(OnProcessExit(target_action=optimizer, on_exit=after_run))
    played = RegisterEventHandler(OnProcessExit(target_action=robot_view, on_exit=after_view))
    return [recorder, *pool, *live, robot_view, optimizer, finished, played]


def after_run(event, context):
    """Return what follows the optimizer's end: shut down, at once if it failed."""
    shutdown = EmitEvent(event=Shutdown(reason='the optimizer finished'))
    return [shutdown] if event.returncode else [TimerAction(period=ROBOT_VIEW_WAIT,
                                                            actions=[shutdown])]


def after_view(event, context):
    """Return what follows the robot view's end: shut down once it played the final design."""
    return [] if event.returncode else [EmitEvent(event=Shutdown(
        reason="the final best design's rollout has played"))]


def generate_launch_description():
    """Return the launch description: its arguments, then the nodes of the run."""
    return LaunchDescription(
        [DeclareLaunchArgument(name, default_value=default, description=description)
         for name, (default, description) in ARGUMENTS.items()]
        + [OpaqueFunction(function=run_nodes)])
