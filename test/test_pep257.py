"""ament's pep257 docstring check over the whole package."""

import pathlib

from ament_pep257.main import main
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
CHECKED = ['hand_codesign', 'test', 'bench', 'tools', 'launch']


@pytest.mark.linter
@pytest.mark.pep257
def test_pep257():
    paths = [str(ROOT / name) for name in CHECKED if (ROOT / name).exists()]
    assert main(argv=paths) == 0, 'Found docstring style errors'
