"""
One world's rollout of a recorded design as a ROS 2 MCAP that Foxglove plays back in 3D.

The file is a ROS 2 bag of standard messages (profile ros2, ros2msg schemas with their
dependencies, cdr messages, closed with its summary and footer), written like a run's bag by
hand_codesign.bag.writer. Per frame of the animation (25 per simulated second):

- contract.REPLAY_MARKERS, visualization_msgs/MarkerArray: the hand drawn from its simulated
  link frames with core.sim.geometry's shapes (the very shapes of the best_design topic), the
  object at its simulated pose, a translucent copy of it at every goal pose;
- contract.REPLAY_GOAL, geometry_msgs/PoseStamped: the goal in effect (the next one due,
  after the last one the last one);
- contract.TF, tf2_msgs/TFMessage: every joint's transform at the frame's joint angles, as the
  robot view node publishes during a run; and once, at time 0, contract.ROBOT_DESCRIPTION (the
  hand's URDF, the text `export` writes) and contract.TF_STATIC (the palm in the world), so
  Foxglove's URDF layer and RViz's RobotModel show the hand moving.

Messages are stamped (header and log time) with the simulated time from 0, so Foxglove's
timeline is the rollout's. They are built by ros.conversions and serialized by rclpy, like
the markers the optimizer node publishes: one path from shapes to bytes (rosbags or
mcap-ros2-support could serialize them without rclpy, but a second conversion would have to
be kept equal to the first).
"""

from builtin_interfaces.msg import Time
from geometry_msgs.msg import PoseStamped
from hand_codesign.analysis.replay import FRAMES_PER_SECOND
from hand_codesign.bag.writer import BagWriteError
from hand_codesign.bag.writer import BagWriter
from hand_codesign.core import contract
from hand_codesign.core.experiments.motion import design_urdf
from hand_codesign.core.experiments.motion import rollout_motion
from hand_codesign.core.sim.geometry import GOAL_COLOUR
from hand_codesign.core.sim.geometry import goal_poses
from hand_codesign.core.sim.geometry import hand_shapes
from hand_codesign.core.sim.geometry import joint_transforms
from hand_codesign.core.sim.geometry import object_shapes
from hand_codesign.core.sim.hand import PALM_LINK
from hand_codesign.core.sim.worlds import object_state
from hand_codesign.core.task.genome import genome_spec
from hand_codesign.errors import UserError
from hand_codesign.outputs import staged
from hand_codesign.ros.conversions import markers_message
from hand_codesign.ros.conversions import robot_description_message
from hand_codesign.ros.conversions import tf_message
from hand_codesign.ros.topics import LOOP_QOS
from hand_codesign.ros.topics import QOS
from rclpy.serialization import serialize_message

NANOSECONDS = 1_000_000_000


def write_rollout_mcap(path, task, design, world):
    """Write one world's rollout of a RecordedDesign as a ROS 2 MCAP; return its frames."""
    if path.exists():
        raise UserError(f'--mcap {path}: already exists; choose a new file')
    physical = genome_spec(task).decode(design.x)
    motion = rollout_motion(physical, task, world, FRAMES_PER_SECOND)
    model, palm = motion.model, motion.palm
    frames = list(zip(motion.times, motion.link_poses, motion.object_poses))
    robot = design_urdf(task, physical, f'{task.name}_candidate{design.candidate_id}')
    state = object_state(task, world)
    goals = goal_poses(task, state) or [(0.0, state.position, state.orientation)]
    shape = task.object_spec.shape
    ghosts = [ghost for _, position, orientation in goals for ghost in object_shapes(
        shape, state.size, (position, orientation), 'goals', GOAL_COLOUR)]
    try:
        with staged(path) as temporary, BagWriter(temporary) as bag:
            for topic, type_name in contract.REPLAY_TOPIC_TYPES.items():
                bag.add_topic('/' + topic, type_name, [QOS.get(topic, LOOP_QOS)])
            write_robot(bag, robot, motion)
            for index, (time, links, object_pose) in enumerate(frames):
                stamp = int(round(time * NANOSECONDS))
                bag.write('/' + contract.TF, serialize_message(tf_message(
                    joint_transforms(motion.model, motion.joint_angles[index]),
                    ros_time(stamp))), log_time=stamp)
                shapes = (hand_shapes(model, palm, links)
                          + object_shapes(shape, state.size, object_pose) + ghosts)
                bag.write('/' + contract.REPLAY_MARKERS,
                          serialize_message(markers_message(shapes, ros_time(stamp))),
                          log_time=stamp)
                bag.write('/' + contract.REPLAY_GOAL,
                          serialize_message(goal_message(current_goal(goals, time), stamp)),
                          log_time=stamp)
    except BagWriteError as error:
        raise UserError(f'--mcap {path}: {error}') from None
    return len(frames)


def write_robot(bag, urdf, motion):
    """Write the hand's robot_description and the palm's fixed place (tf_static) at time 0."""
    bag.write('/' + contract.ROBOT_DESCRIPTION,
              serialize_message(robot_description_message(urdf)), log_time=0)
    bag.write('/' + contract.TF_STATIC, serialize_message(tf_message(
        [(contract.WORLD_FRAME, PALM_LINK, motion.palm)], ros_time(0))), log_time=0)


def current_goal(goals, time):
    """Return the goal (time, position, orientation) in effect at `time`: the next one due."""
    return next((goal for goal in goals if goal[0] >= time - 1e-9), goals[-1])


def ros_time(nanoseconds):
    """Return the builtin_interfaces/Time of a number of nanoseconds."""
    return Time(sec=nanoseconds // NANOSECONDS, nanosec=nanoseconds % NANOSECONDS)


def goal_message(goal, stamp):
    """Return the PoseStamped of a goal (time, position, orientation), stamped at `stamp` ns."""
    message = PoseStamped()
    message.header.frame_id = contract.WORLD_FRAME
    message.header.stamp = ros_time(stamp)
    _, position, orientation = goal
    pose = message.pose
    pose.position.x, pose.position.y, pose.position.z = (float(v) for v in position)
    pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w = (
        float(v) for v in orientation)
    return message
