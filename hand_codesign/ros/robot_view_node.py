"""
The robot view node: the run's best design as a robot model that RViz and Foxglove show moving.

It hears the run's RunInfo and generation summaries. On each new best design it decodes the
summary's genome on the run's task (as the optimizer draws the best_design markers),
re-simulates its rollout in world `world` (core.experiments.motion) and publishes
- robot_description (std_msgs/String, transient local): the hand's URDF, the text
  `hand-codesign export` writes as hand.urdf;
- tf_static (tf2_msgs/TFMessage, transient local): the palm fixed in the world frame;
- tf: every joint's transform (core.sim.geometry.joint_transforms), frame by frame in real
  time, 25 frames per simulated second: what robot_state_publisher gives from joint states.
After the last frame the hand rests (`loop`: the rollout plays again). Once the final best
design's rollout has played, the node ends, so a runner that waits for it closes a bag that
holds that whole motion. Summaries arriving together are looked at once, the last one.
"""

import sys

from hand_codesign.core import contract
from hand_codesign.core.experiments.motion import design_urdf
from hand_codesign.core.experiments.motion import FRAMES_PER_SECOND
from hand_codesign.core.experiments.motion import rollout_motion
from hand_codesign.core.run.runs import run_task
from hand_codesign.core.sim.geometry import joint_transforms
from hand_codesign.core.sim.hand import PALM_LINK
from hand_codesign.core.sim.worlds import world_states
from hand_codesign.core.task.genome import genome_spec
from hand_codesign.core.task.variant import Variant
from hand_codesign.ros import topics
from hand_codesign.ros.conversions import robot_description_message
from hand_codesign.ros.conversions import stamp_now
from hand_codesign.ros.conversions import tf_message
from hand_codesign.ros.node_main import run_node
from hand_codesign.ros.parameters import declare_read_only
from hand_codesign_msgs.msg import GenerationSummary
from hand_codesign_msgs.msg import RunInfo
from rclpy.node import Node
from rclpy.task import Future

PARAMETERS = {
    'world': (0, "the world state whose rollout is shown (the run's index)", (0, 10**6)),
    'loop': (False, 'play the rollout again and again; false: once per new best design', None),
    'end_after_final': (True, "end once the final best design's rollout has played", None),
}


class RobotView(Node):
    """Publish the best design's URDF and its rollout's transforms."""

    def __init__(self):
        super().__init__('robot_view')
        self.settings = declare_read_only(self, PARAMETERS)
        self.finished = Future()
        self.run_info = self.latest = self.shown = None
        self.frames, self.index, self.final = [], 0, False
        self.publishers_ = {name: self.create_publisher(
            topics.VIEW_MESSAGE_TYPES[name], name, topics.QOS[name])
            for name in contract.ROBOT_TOPIC_TYPES}
        self.create_subscription(RunInfo, contract.RUN_INFO, self.on_run_info,
                                 topics.QOS[contract.RUN_INFO])
        self.create_subscription(GenerationSummary, contract.GENERATION_SUMMARY,
                                 self.on_summary, topics.QOS[contract.GENERATION_SUMMARY])
        self.create_timer(1.0 / FRAMES_PER_SECOND, self.play)
        self.get_logger().info(f'{contract.ROBOT_VIEW_READY}: publishing '
                               f'{", ".join(contract.ROBOT_TOPIC_TYPES)}')

    def on_run_info(self, message):
        if self.run_info is None:  # the run's own comes first (a resumed run's too)
            self.run_info = message

    def on_summary(self, message):
        self.latest = message  # kept until the RunInfo is there: topics arrive in any order

    def play(self):
        """Show a new best design if one came, then publish the next frame of the rollout."""
        summary = self.latest if self.run_info is not None else None
        if summary is not None:
            self.latest = None
        if summary is not None and summary.run_id == self.run_info.run_id:
            self.final = self.final or summary.final
            design = (summary.best_candidate_id, tuple(summary.structure))
            if design != self.shown:
                self.shown = design
                self.show(summary)
        if self.index < len(self.frames):
            self.publishers_[contract.TF].publish(tf_message(self.frames[self.index],
                                                             stamp_now(self)))
            self.index += 1
            if self.index == len(self.frames) and self.settings['loop']:
                self.index = 0
        elif self.final and self.settings['end_after_final'] and not self.finished.done():
            self.finished.set_result(True)

    def show(self, summary):
        """Re-simulate a summary's best design; publish its URDF and palm, queue its frames."""
        info = self.run_info
        try:
            task = run_task(info.task_yaml, f'run {info.run_id} task', info.seed,
                            info.iterations, info.population, info.world_states,
                            Variant(structure=tuple(summary.structure)), info.engine)
            design = genome_spec(task).decode(list(summary.best_genome))
            worlds = world_states(task)
            world = worlds[min(self.settings['world'], len(worlds) - 1)]
            motion = rollout_motion(design, task, world)
        except ValueError as error:  # TaskError and a genome of another size among them
            self.get_logger().warning(f'best design {summary.best_candidate_id}: cannot '
                                      f'show it: {error}')
            return
        name = f'{task.name}_candidate{summary.best_candidate_id}'
        stamp = stamp_now(self)
        self.publishers_[contract.ROBOT_DESCRIPTION].publish(
            robot_description_message(design_urdf(task, design, name)))
        self.publishers_[contract.TF_STATIC].publish(
            tf_message([(contract.WORLD_FRAME, PALM_LINK, motion.palm)], stamp))
        self.frames = [joint_transforms(motion.model, angles) for angles in motion.joint_angles]
        self.index = 0
        self.get_logger().info(f'showing best design {summary.best_candidate_id} (structure '
                               f'{list(summary.structure)}): {len(self.frames)} frames')


def main(args=None):
    return run_node(RobotView, 'robot_view', args, until=lambda node: node.finished)


if __name__ == '__main__':
    sys.exit(main())
