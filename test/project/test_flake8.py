"""ament's flake8 check (ROS 2 configuration) over the whole package."""

import pathlib

from ament_flake8.main import main_with_errors
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
CHECKED = ['hand_codesign', 'test', 'bench', 'tools', 'launch', 'setup.py']


@pytest.mark.flake8
@pytest.mark.linter
def test_flake8():
    paths = [str(ROOT / name) for name in CHECKED if (ROOT / name).exists()]
    rc, errors = main_with_errors(argv=paths)
    assert rc == 0, f'Found {len(errors)} code style errors / warnings:\n' + '\n'.join(errors)
