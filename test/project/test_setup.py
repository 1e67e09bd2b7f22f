"""The set-up step of `make`: a clear message for a missing system tool, and no-op when current."""

import os
import pathlib
import shutil
import subprocess
import sys

import pytest

pytestmark = pytest.mark.system

ROOT = pathlib.Path(__file__).resolve().parents[2]


def tools_without(tmp_path, missing):
    """Return a PATH folder with links to the system tools the check needs, but `missing`."""
    folder = tmp_path / 'bin'
    folder.mkdir()
    # the interpreter the venv was made from: a shim (pyenv) would need its own PATH
    (folder / 'python3').symlink_to(pathlib.Path(sys.base_prefix, 'bin', 'python3'))
    for tool in ['cmake', 'cc', 'c++', 'make', 'bash']:
        found = shutil.which(tool)
        if tool != missing and found:
            (folder / tool).symlink_to(found)
    return str(folder)


def check_system(path):
    return subprocess.run(['bash', str(ROOT / 'tools' / 'check_system.sh')],
                          env=dict(os.environ, PATH=path), capture_output=True, text=True,
                          timeout=60)


def test_all_tools_present_passes(tmp_path):
    result = check_system(tools_without(tmp_path, missing=None))
    assert result.returncode == 0, result.stderr


def test_missing_cmake_is_named_with_its_package(tmp_path):
    result = check_system(tools_without(tmp_path, missing='cmake'))
    assert result.returncode == 1
    assert 'cmake (Debian package cmake)' in result.stderr


def test_missing_compiler_is_named_with_its_package(tmp_path):
    result = check_system(tools_without(tmp_path, missing='c++'))
    assert result.returncode == 1
    assert 'Debian package g++' in result.stderr


def test_setup_is_up_to_date_after_make():
    result = subprocess.run(['make', '--question', 'setup'], cwd=ROOT, capture_output=True,
                            text=True, timeout=60)
    assert result.returncode == 0, 'make would rebuild part of .venv although nothing changed'
