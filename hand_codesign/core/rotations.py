"""
Rotations as unit quaternions (x, y, z, w), PyBullet's order: the one home of this math.

Eq. (4)'s angle between two orientations is an objective and lives in core/sim/objectives.py;
everything here is plain geometry that the task reader, the worlds and the objectives share.
"""

import math

import numpy as np


def axis_angle_quaternion(axis, angle):
    """Return the unit quaternion (x, y, z, w) rotating by `angle` about unit `axis`."""
    half = angle / 2
    sine = math.sin(half)
    return tuple(float(v) + 0.0 for v in (axis[0] * sine, axis[1] * sine, axis[2] * sine,
                                          math.cos(half)))


def quaternion_multiply(first, second):
    """Return the Hamilton product first * second of quaternions (x, y, z, w)."""
    x1, y1, z1, w1 = first
    x2, y2, z2, w2 = second
    return (w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2)


def quaternion_conjugate(quaternion):
    """Return the conjugate (the inverse of a unit quaternion) of (x, y, z, w)."""
    x, y, z, w = quaternion
    return (-x, -y, -z, w)


def vertical_turn(start, end):
    """
    Return the turn (rad, in [-pi, pi]) about the vertical from orientation start to end.

    Both are quaternions (x, y, z, w) in the world frame; the turn is the twist about the
    world's z axis of the rotation that takes start to end (its swing, a tilt, is left out).
    """
    x, y, z, w = quaternion_multiply(end, quaternion_conjugate(start))
    return float(np.angle(np.exp(2j * math.atan2(z, w))))


def rotation_matrix(quaternion):
    """Return the 3 x 3 rotation matrix of a unit quaternion (x, y, z, w)."""
    x, y, z, w = quaternion
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def slerp(start, end, fraction):
    """Return the unit quaternion a `fraction` of the shortest rotation from start to end."""
    start = np.asarray(start, dtype=float)
    end = np.asarray(end, dtype=float)
    inner = float(np.dot(start, end))
    if inner < 0.0:  # q and -q are one rotation: take the short way round
        end, inner = -end, -inner
    if inner > 0.9995:
        result = start + fraction * (end - start)
    else:
        angle = math.acos(min(inner, 1.0))
        result = (math.sin((1.0 - fraction) * angle) * start
                  + math.sin(fraction * angle) * end) / math.sin(angle)
    return result / np.linalg.norm(result)


def rotate(quaternion, vector):
    """Return a vector turned by a unit quaternion (x, y, z, w)."""
    x, y, z, w = quaternion
    turned = quaternion_multiply(quaternion_multiply(quaternion, (*vector, 0.0)),
                                 (-x, -y, -z, w))
    return tuple(float(v) for v in turned[:3])


def compose(first, second):
    """Return the pose `second` (given in the frame `first`) in the frame of `first`'s parent."""
    (p1, q1), (p2, q2) = first, second
    moved = rotate(q1, p2)
    orientation = quaternion_multiply(q1, q2)
    return (tuple(float(a + b) for a, b in zip(p1, moved)),
            tuple(float(v) for v in orientation))
