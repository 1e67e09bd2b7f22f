"""
The recorder node: writes every message of the co-design loop to a rosbag2-compatible MCAP bag.

It subscribes to the loop's topics without decoding (raw CDR), losslessly (ros.recording has
its QoS, parameters and bag), and writes every message as it arrives, flushed every
``flush_period`` s: a recorder killed with SIGKILL loses at most that, and one started with
continue_bag continues its bag (bag.recovery). SIGINT and SIGTERM stop it cleanly: it takes
what has arrived, then closes the bag. Once subscribed it logs contract.RECORDER_READY.
"""

import signal
import sys
import time

from hand_codesign.core.contract import RECORDER_READY
from hand_codesign.ros import topics
from hand_codesign.ros.lifeline import follow_runner
from hand_codesign.ros.parameters import declare_read_only
from hand_codesign.ros.recording import open_bag
from hand_codesign.ros.recording import PARAMETERS
from hand_codesign.ros.recording import recorder_qos
from hand_codesign.ros.recording import RecorderError
import rclpy
from rclpy.exceptions import ParameterException
from rclpy.executors import ExternalShutdownException
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions

# How long the recorder keeps taking messages that already arrived once asked to stop, and how
# long the topics must stay quiet before it closes the bag.
DRAIN_TIMEOUT = 3.0
DRAIN_QUIET = 0.2
SPIN_PERIOD = 0.05


class Recorder(Node):
    """Record the loop's topics to an MCAP bag until asked to stop."""

    def __init__(self):
        """Declare the parameters, create the bag and subscribe to every topic to record."""
        super().__init__('recorder')
        self.settings = declare_read_only(self, PARAMETERS)
        self.bag = open_bag(self.settings)
        self._stop_requests = 0
        self._last_message_time = time.monotonic()
        self.subscriptions_by_topic = {}
        for name in self.settings['topics']:
            subscription = self.create_subscription(
                topics.RECORDED_MESSAGE_TYPES[name], name, self._record_callback(name),
                recorder_qos(topics.QOS[name]), raw=True)
            self.subscriptions_by_topic[subscription.topic_name] = subscription
        self.flush_timer = self.create_timer(self.settings['flush_period'], self.flush)
        self.get_logger().info(
            f'{RECORDER_READY}: recording {", ".join(self.subscriptions_by_topic)} to '
            f'{self.bag.file_path}')

    def _record_callback(self, name):
        """Return the raw subscription callback that writes the messages of topic name."""
        type_name = topics.type_name(topics.RECORDED_MESSAGE_TYPES[name])
        declared_qos = topics.QOS[name]
        resolved = []  # the resolved (absolute) name, known once the subscription exists

        def record(data, message_info):
            log_time = time.time_ns()
            resolved[:] = resolved or [self.resolve_topic_name(name)]
            topic = resolved[0]
            if not self.bag.has_topic(topic):
                self.bag.add_topic(topic, type_name, self._offered_qos(topic, declared_qos))
            publish_time = message_info.get('source_timestamp') or log_time
            self.bag.write(topic, data, log_time=log_time, publish_time=publish_time)
            self._last_message_time = time.monotonic()

        return record

    def _offered_qos(self, topic, declared_qos):
        """Return the QoS profiles the publishers of topic offer now, as rosbag2 records them."""
        profiles = [info.qos_profile for info in self.get_publishers_info_by_topic(topic)]
        # A publisher that already left is not in the graph: its topic's declared QoS stands in.
        return profiles or [declared_qos]

    def flush(self):
        """Write what arrived since the last flush to disk."""
        if not self.bag.closed:
            self.bag.flush()

    def request_stop(self, signal_number=None, frame=None):
        """Ask the recorder to stop (signal handler for SIGINT and SIGTERM)."""
        self._stop_requests += 1

    def spin_until_stopped(self, executor):
        """Record until a stop is requested, then take what has arrived and return."""
        while not self._stop_requests:
            executor.spin_once(timeout_sec=SPIN_PERIOD)
        self.get_logger().info('stopping: taking the messages that already arrived')
        deadline = time.monotonic() + DRAIN_TIMEOUT
        self._last_message_time = time.monotonic()
        while (self._stop_requests < 2 and time.monotonic() < deadline
               and time.monotonic() - self._last_message_time < DRAIN_QUIET):
            executor.spin_once(timeout_sec=SPIN_PERIOD / 5)

    def close_bag(self):
        """Close the bag (summary and footer) and log what it holds; idempotent."""
        if not self.bag.closed:
            self.bag.close()
            counts = ', '.join(f'{topic}: {n}' for topic, n in self.bag.message_counts.items())
            self.get_logger().info(
                f'closed {self.bag.file_path} with {self.bag.message_count} messages '
                f'({counts or "none"})')

    def destroy_node(self):
        """Close the bag, then destroy the node."""
        self.close_bag()
        super().destroy_node()


def main(args=None):
    """Run the recorder until SIGINT or SIGTERM; return the exit status."""
    # Our own handlers, not rclpy's: rclpy's would shut the context down at once, before the
    # messages that already arrived are taken and written.
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    early_signals = []
    signal.signal(signal.SIGINT, lambda number, frame: early_signals.append(number))
    signal.signal(signal.SIGTERM, lambda number, frame: early_signals.append(number))
    follow_runner()   # a runner that dies sends SIGTERM: the bag is closed
    recorder = None
    status = 0
    try:
        recorder = Recorder()
        signal.signal(signal.SIGINT, recorder.request_stop)
        signal.signal(signal.SIGTERM, recorder.request_stop)
        for number in early_signals:
            recorder.request_stop(number)
        executor = SingleThreadedExecutor()
        executor.add_node(recorder)
        recorder.spin_until_stopped(executor)
    except (RecorderError, ParameterException) as error:
        rclpy.logging.get_logger('recorder').error(str(error))
        status = 2
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if recorder is not None:
            recorder.destroy_node()
        rclpy.try_shutdown()
    return status


if __name__ == '__main__':
    sys.exit(main())
