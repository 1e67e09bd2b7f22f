"""Node parameters declared from one table, read-only and with their ranges, read once."""

from rcl_interfaces.msg import FloatingPointRange
from rcl_interfaces.msg import IntegerRange
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.node import Node
from rclpy.parameter import Parameter


def descriptor(default, description, bounds):
    """Return the read-only ParameterDescriptor of a parameter, with its range if bounded."""
    result = ParameterDescriptor(description=description, read_only=True)
    if bounds is not None and isinstance(default, float):
        result.floating_point_range = [FloatingPointRange(
            from_value=float(bounds[0]), to_value=float(bounds[1]), step=0.0)]
    elif bounds is not None:
        result.integer_range = [IntegerRange(
            from_value=int(bounds[0]), to_value=int(bounds[1]), step=1)]
    return result


def declare_read_only(node, table):
    """
    Declare the parameters of table (name -> (default, description, bounds or None)).

    Return {name: value}: the node reads its parameters once, here, so that what it runs with
    is what was given at start. A value outside its range raises rclpy's
    InvalidParameterValueException, naming the parameter and the range.
    """
    return {name: node.declare_parameter(name, default,
                                         descriptor(default, description, bounds)).value
            for name, (default, description, bounds) in table.items()}


def read_before_start(name, table):
    """
    Return {name: value} of table's parameters as a node called `name` would be given them.

    For a node whose own name depends on its parameters (an evaluator is named after its id):
    a short-lived node without services or /rosout reads them, so that a parameter file keyed
    by the usual name still reaches the node under its final one.
    """
    reader = Node(name, start_parameter_services=False, enable_rosout=False)
    try:
        return declare_read_only(reader, table)
    finally:
        reader.destroy_node()


def overrides(settings):
    """Return {name: value} as the Parameter list of Node's parameter_overrides argument."""
    return [Parameter(name, value=value) for name, value in settings.items()]
