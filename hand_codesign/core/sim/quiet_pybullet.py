"""
PyBullet without its start-up chatter.

PyBullet prints its build time from C when it is imported and `argv[0]=` when a client
connects; in a command's output or an evaluator's log that is noise. Both are written by C
code straight to the process's standard streams, so those are pointed at /dev/null, only
while importing and connecting (errors still arrive as Python exceptions).
"""

import contextlib
import ctypes
import os
import sys

_LIBC = ctypes.CDLL(None)
_STREAMS = (1, 2)


@contextlib.contextmanager
def c_output_silenced():
    """Send what C code writes to standard output and error to /dev/null for the block."""
    sys.stdout.flush()
    sys.stderr.flush()
    try:
        saved = [os.dup(descriptor) for descriptor in _STREAMS]
    except OSError:  # a stream is closed: nothing to silence
        yield
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    for descriptor in _STREAMS:
        os.dup2(devnull, descriptor)
    try:
        yield
    finally:
        # C's stdio buffers its output when it is not a terminal: flush it while the
        # descriptors still point to /dev/null
        _LIBC.fflush(None)
        for descriptor, original in zip(_STREAMS, saved):
            os.dup2(original, descriptor)
            os.close(original)
        os.close(devnull)


def _load():
    with c_output_silenced():
        import pybullet
        from pybullet_utils import bullet_client
    return pybullet, bullet_client.BulletClient


pybullet, BulletClient = _load()
