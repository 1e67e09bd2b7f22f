"""
Reading the values of a task file: numbers, vectors, bounds, quaternions, each checked.

`ValueReader` is the base of the task's readers (core.task.reader, core.task.settings_reader,
core.task.design_reader): each value comes with its dotted key, and a mistake is one TaskError
naming the file, the key, what was expected and what came.
"""

import math
import re

from hand_codesign.core.rotations import axis_angle_quaternion
from hand_codesign.core.task.parts import Bounds, TaskError
import numpy as np


class ValueReader:
    """Reads one value of the parsed YAML at a time, naming its dotted key in errors."""

    def __init__(self, source):
        self.source = source

    def fail(self, key, expected, value=None, got=True):
        text = f'{self.source}: {key}: expected {expected}'
        if got:
            text += f', got {value!r}'
        raise TaskError(text)

    # ---- generic values

    def mapping(self, value, key, required=(), optional=()):
        if not isinstance(value, dict):
            self.fail(key or 'top level', 'a mapping', value)
        for name in value:
            if name not in required and name not in optional:
                allowed = ', '.join(list(required) + list(optional))
                self.fail(join_key(key, str(name)), f'no such key (allowed: {allowed})',
                          got=False)
        for name in required:
            if name not in value:
                self.fail(join_key(key, name), 'this key (it is missing)', got=False)
        return value

    def number(self, value, key, minimum=None, positive=False, angle=False):
        number = _angle_expression(value) if angle and isinstance(value, str) else value
        if isinstance(number, bool) or not isinstance(number, (int, float)) \
                or not math.isfinite(number):
            self.fail(key, 'a number', value)
        number = float(number)
        if positive and not number > 0:
            self.fail(key, 'a positive number', value)
        if minimum is not None and number < minimum:
            self.fail(key, f'a number >= {minimum}', value)
        return number

    def integer(self, value, key, minimum=1):
        if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
            what = 'a positive integer' if minimum == 1 else f'an integer >= {minimum}'
            self.fail(key, what, value)
        return int(value)

    def boolean(self, value, key):
        if not isinstance(value, bool):
            self.fail(key, 'true or false', value)
        return value

    def choice(self, value, key, choices):
        if value not in choices:
            self.fail(key, 'one of ' + ', '.join(choices), value)
        return value

    def text(self, value, key):
        if not isinstance(value, str) or not value.strip():
            self.fail(key, 'a non-empty string', value)
        return value

    def vector(self, value, key, size, positive=False, angle=False, minimum=None):
        if not isinstance(value, list) or len(value) != size:
            self.fail(key, f'a list of {size} numbers', value)
        return tuple(self.number(item, f'{key}[{index}]', positive=positive, angle=angle,
                                 minimum=minimum)
                     for index, item in enumerate(value))

    def bounds(self, value, key, angle=False, minimum=None):
        if not isinstance(value, list) or len(value) != 2:
            self.fail(key, 'a pair [lower, upper]', value)
        lower, upper = (self.number(item, f'{key}[{index}]', angle=angle, minimum=minimum)
                        for index, item in enumerate(value))
        if lower > upper:
            self.fail(key, 'lower <= upper', value)
        return Bounds(lower, upper)

    def quaternion(self, value, key):
        if isinstance(value, dict):
            self.mapping(value, key, required=('axis', 'angle'))
            axis = self.unit_vector(value['axis'], join_key(key, 'axis'))
            angle = self.number(value['angle'], join_key(key, 'angle'), angle=True)
            return axis_angle_quaternion(axis, angle)
        if not isinstance(value, list) or len(value) != 4:
            self.fail(key, 'a quaternion [x, y, z, w] or {axis: [x, y, z], angle: rad}',
                      value)
        return self._normalized(value, key, 4, 'quaternion')

    def unit_vector(self, value, key):
        return self._normalized(value, key, 3, 'vector')

    def _normalized(self, value, key, size, what):
        vector = np.array(self.vector(value, key, size))
        norm = np.linalg.norm(vector)
        if norm < 1e-9:
            self.fail(key, f'a non-zero {what}', value)
        return tuple(float(v) for v in vector / norm)

    def items(self, value, key, what, parse):
        """Return parse(item, 'key[index]') for each item of a non-empty list of `what`."""
        if not isinstance(value, list) or not value:
            self.fail(key, f'a non-empty list of {what}', value)
        return tuple(parse(item, f'{key}[{index}]') for index, item in enumerate(value))

    def structure(self, value, key):
        return self.items(value, key, 'joints per finger, e.g. [2, 2]', self.integer)

    # ---- sections


def join_key(prefix, name):
    """Return the dotted key of `name` under `prefix`."""
    return f'{prefix}.{name}' if prefix else name


_ANGLE = re.compile(r'^\s*(-)?\s*(?:(\d+(?:\.\d*)?)\s*\*\s*)?pi\s*(?:/\s*(\d+(?:\.\d*)?))?\s*$')


def _angle_expression(text):
    """Return the value of '[-][k*]pi[/d]' or the text itself when it is not one."""
    match = _ANGLE.match(text)
    if not match:
        return text
    sign, factor, divisor = match.groups()
    value = math.pi * float(factor or 1) / float(divisor or 1)
    return -value if sign else value
