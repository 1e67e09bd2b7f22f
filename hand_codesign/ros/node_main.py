"""
The `main` every node of a run shares: start rclpy, build the node, spin it, shut down.

A user's mistake (a bad parameter, a task the node cannot run) is one error line and exit
status 2, never a traceback; Ctrl-C and an external shutdown end the node normally (0).
"""

import threading

from hand_codesign.deprecation import show_old_names
from hand_codesign.errors import UserError
from hand_codesign.ros.lifeline import follow_runner
import rclpy
from rclpy.exceptions import ParameterException
from rclpy.executors import ExternalShutdownException
from rclpy.executors import SingleThreadedExecutor


def run_node(make_node, logger_name, args=None, errors=(), until=None, farewell=None,
             spin=None):
    """
    Spin the node `make_node()` builds until shutdown; return the process's exit status.

    errors: more exception types that mean a user's mistake. until: a function of the node
    returning the Future whose completion ends the spin (None: spin until shutdown).
    farewell: a function of the node called once it is destroyed, e.g. to log what it did.
    spin: a function of (node, executor) that spins the node its own way instead of
    rclpy.spin, with a SingleThreadedExecutor. A node a runner started ends with the runner
    (ros.lifeline).
    """
    follow_runner()
    show_old_names(rclpy.logging.get_logger(logger_name).warning)  # an old task key, one line
    rclpy.init(args=args)
    node = None
    spinner = None
    try:
        node = make_node()
        if spin is not None:
            spinner = SingleThreadedExecutor()
            spinner.add_node(node)
            spin(node, spinner)
        elif until is None:
            rclpy.spin(node)
        else:
            rclpy.spin_until_future_complete(node, until(node))
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except (ParameterException, UserError, *errors) as error:
        rclpy.logging.get_logger(logger_name).error(str(error))
        return 2
    finally:
        if spinner is not None:
            spinner.shutdown()
        if node is not None:
            node.destroy_node()
            if farewell is not None:
                farewell(node)
        rclpy.try_shutdown()
    return 0


def on_line(stream, node, callback):
    """
    Return an Event set once a line arrives on stream (never if it closes first).

    callback then runs in the node's executor: a process that starts the node tells it
    something this way, e.g. ros.runner that the run's recorder records.
    """
    arrived = threading.Event()
    guard = node.create_guard_condition(callback)

    def wait():
        if stream.readline():
            arrived.set()
            guard.trigger()

    threading.Thread(target=wait, daemon=True).start()
    return arrived


def take_arrived(executor, heard, timeout):
    """
    Run the callbacks of every message that arrived, waiting up to timeout s for the first.

    rclpy's spin_once runs one callback. heard() counts the messages the node's callbacks
    took: while it grows, more may be waiting (an evaluator hears every evaluator's candidates,
    and one at a time they kept its own next candidate waiting until it had run dry).
    """
    count = heard()
    executor.spin_once(timeout_sec=timeout)
    while heard() > count:
        count = heard()
        executor.spin_once(timeout_sec=0.0)
