"""Test session set-up shared by every test file."""

import os
import sys

import hand_codesign  # noqa: F401  first: it pins numpy's and OpenBLAS's kernels (arithmetic)

# The ROS 2 wheels do not set AMENT_PREFIX_PATH; `make test` does, a bare pytest may not.
os.environ.setdefault('AMENT_PREFIX_PATH', sys.prefix)
os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')

# One short real run (`hand-codesign run`) shared by the analysis tests, made once per session.
from analysis_run import real_run  # noqa: E402, F401, I100
