"""Test session set-up shared by every test file."""

import os
import sys

import hand_codesign  # noqa: F401  first: it pins numpy's and OpenBLAS's kernels (arithmetic)

# The tests mirror the package (test/core/sim, test/ros, ...); a test imports the helpers
# (test/helpers) and other rooms' test modules by name, so every folder of test/ is on the path.
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), 'helpers'))
from layout import FOLDERS  # noqa: E402, I100
sys.path[1:1] = [str(folder) for folder in FOLDERS[1:] if str(folder) not in sys.path]

# The ROS 2 wheels do not set AMENT_PREFIX_PATH; `make test` does, a bare pytest may not.
os.environ.setdefault('AMENT_PREFIX_PATH', sys.prefix)
os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')

# One short real run (`hand-codesign run`) shared by the analysis tests, made once per session.
from analysis_run import real_run  # noqa: E402, F401, I100
