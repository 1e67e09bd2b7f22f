"""
The live view node: serves a run's topics to Foxglove over its WebSocket protocol, as they come.

It subscribes to every topic a run records (the loop's, the best design's markers, the robot
view's robot_description, tf_static and tf) without decoding (raw CDR) and logs each message
on a channel of the Foxglove SDK's server
(`foxglove-sdk`) with the schema the bag holds: the type's ros2msg definition with its
dependencies, message encoding cdr. So Foxglove (or Lichtblick) decodes the live run exactly
like its bag, and the same layout (config/foxglove_layout.json) shows both. A client that
subscribes late first gets the last message of the topic again, like a latched topic: the best
design so far and the last summary show at once. It serves on 127.0.0.1 unless `host` says
otherwise. Once serving, it logs contract.LIVE_READY and the address.
"""

import collections
import sys
import time

import foxglove
from hand_codesign.bag.metadata import MESSAGE_ENCODING
from hand_codesign.bag.writer import message_definition
from hand_codesign.bag.writer import SCHEMA_ENCODING
from hand_codesign.core.contract import LIVE_READY
from hand_codesign.errors import UserError
from hand_codesign.ros import topics
from hand_codesign.ros.node_main import run_node
from hand_codesign.ros.parameters import declare_read_only
from hand_codesign.ros.recording import recorder_qos
from rclpy.node import Node

PARAMETERS = {
    'host': ('127.0.0.1', 'address to serve on (127.0.0.1: this host only)', None),
    'port': (8765, 'TCP port of the WebSocket server; 0 picks a free one', (0, 65535)),
}
REPEAT_PERIOD = 0.1  # s between looks at the subscriptions that wait for their last message


class LiveView(Node):
    """Forward the run's messages to a Foxglove WebSocket server."""

    def __init__(self):
        super().__init__('live_view')
        self.settings = declare_read_only(self, PARAMETERS)
        self.channels, self.last = {}, {}
        self.repeat = collections.deque()  # topics a client subscribed to, appended by the server
        for name, message_type in topics.RECORDED_MESSAGE_TYPES.items():
            type_name = topics.type_name(message_type)
            schema = foxglove.Schema(name=type_name, encoding=SCHEMA_ENCODING,
                                     data=message_definition(type_name).encode('utf-8'))
            topic = self.resolve_topic_name(name)
            self.channels[topic] = foxglove.Channel(topic, schema=schema,
                                                    message_encoding=MESSAGE_ENCODING)
            self.create_subscription(message_type, name, self.forwarder(topic),
                                     recorder_qos(topics.QOS[name]), raw=True)
        try:
            self.server = foxglove.start_server(
                name='hand_codesign', host=self.settings['host'], port=self.settings['port'],
                server_listener=self)
        except Exception as error:  # noqa: B902 the SDK raises its own, undocumented errors
            raise UserError(f'parameters host, port: cannot serve on '
                            f'{self.settings["host"]}:{self.settings["port"]}: {error}')
        self.create_timer(REPEAT_PERIOD, self.repeat_last)
        self.get_logger().info(
            f'{LIVE_READY}: ws://{self.settings["host"]}:{self.server.port} serving '
            f'{", ".join(self.channels)}')

    def forwarder(self, topic):
        """Return the raw subscription callback that logs a topic's messages to the server."""
        channel = self.channels[topic]

        def forward(data):
            self.last[topic] = data
            channel.log(data, log_time=time.time_ns())
        return forward

    def on_subscribe(self, client, channel):
        """Note a client's subscription (called on the server's thread)."""
        self.repeat.append(channel.topic)

    def repeat_last(self):
        """Log the last message of each topic a client subscribed to since the last look."""
        while self.repeat:
            topic = self.repeat.popleft()
            if topic in self.last:
                self.channels[topic].log(self.last[topic], log_time=time.time_ns())

    def destroy_node(self):
        """Stop the server, then destroy the node."""
        if getattr(self, 'server', None) is not None:
            self.server.stop()
        super().destroy_node()


def main(args=None):
    return run_node(LiveView, 'live_view', args)


if __name__ == '__main__':
    sys.exit(main())
