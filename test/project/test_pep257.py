"""ament's pep257 docstring check over the whole package."""

import pathlib

from ament_pep257.main import main
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
CHECKED = ['hand_codesign', 'test', 'bench', 'tools', 'launch']
# Public entry points document their arguments in Google style (`Args:`, `Returns:`), as
# dm_control does; these checks are numpy style's underlined sections, which Google style has not
GOOGLE_SECTIONS = ['D406', 'D407', 'D408', 'D409', 'D413']


@pytest.mark.linter
@pytest.mark.pep257
def test_pep257():
    paths = [str(ROOT / name) for name in CHECKED if (ROOT / name).exists()]
    assert main(argv=[*paths, '--add-ignore', *GOOGLE_SECTIONS]) == 0, (
        'Found docstring style errors')
