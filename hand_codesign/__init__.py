"""Evolutionary co-design of robot hands and their control (Meixner, Hazard, Pollard)."""

import os
import sys

from hand_codesign.arithmetic import pin

# Before anything imports numpy: the same numpy and OpenBLAS kernels on every x86-64
# processor with AVX2, in this process and the ones it starts (hand_codesign.arithmetic).
ARITHMETIC = pin()

# The ROS 2 wheels from PyPI do not set AMENT_PREFIX_PATH, and ament_index_python (message
# types, the middleware) raises without it. Every entry point imports this package first (the
# `hand-codesign` command, the nodes started with `python -m` or `ros2 run`), so a plain shell
# works as well as `make`; a sourced ROS workspace keeps its own value.
if not os.environ.get('AMENT_PREFIX_PATH'):
    os.environ['AMENT_PREFIX_PATH'] = sys.prefix
