"""
Python 3.11, 3.12 and 3.13: `make` accepts each, and the pinned requirements resolve for each.

Only one Python may be installed here, so the requirements are resolved by pip's own resolver
for the others (`pip install --dry-run --python-version`, test/helpers/pip_resolution.py); the
check of `make` runs tools/check_system.sh with a `python3` that reports each version.
"""

import os
import pathlib
import shutil
import subprocess
import sys

from pip_resolution import (build_source_wheels, COMPILED_HERE, normalized, pins,
                            requirement_lines, resolve, resolve_compiled_here)
import pytest

pytestmark = pytest.mark.system

ROOT = pathlib.Path(__file__).resolve().parents[2]
VERSIONS = ('3.11', '3.12', '3.13')


@pytest.fixture(scope='module')
def source_wheels(tmp_path_factory):
    return build_source_wheels(tmp_path_factory.mktemp('source-wheels'))


def python_reporting(folder, version):
    """Write a `python3` into folder that says it is `version` and is this Python otherwise."""
    folder.mkdir()
    script = folder / 'python3'
    script.write_text(
        '#!/bin/sh\n'
        f'case "$2" in *version_info*) echo {version}; exit 0;; esac\n'
        f'exec {sys.base_prefix}/bin/python3 "$@"\n')
    script.chmod(0o755)
    for tool in ['cmake', 'cc', 'c++', 'make', 'bash']:
        if shutil.which(tool):
            (folder / tool).symlink_to(shutil.which(tool))
    return str(folder)


@pytest.mark.parametrize('version', VERSIONS + ('3.10', '3.14'))
def test_make_accepts_python_3_11_to_3_13_only(tmp_path, version):
    path = python_reporting(tmp_path / 'bin', version)
    result = subprocess.run(['bash', str(ROOT / 'tools' / 'check_system.sh')],
                            env=dict(os.environ, PATH=path), capture_output=True, text=True,
                            timeout=60)
    if version in VERSIONS:
        assert result.returncode == 0, result.stderr
        assert f'python{version}' in result.stdout
    else:
        assert result.returncode == 1
        assert f'Python 3.11, 3.12 or 3.13 as python3 (it is {version}' in result.stderr


@pytest.mark.parametrize('version', VERSIONS)
def test_pinned_requirements_resolve_for(version, tmp_path, source_wheels):
    lock = pins(ROOT / 'requirements-lock.txt', version)
    top = pins(ROOT / 'requirements.txt', version)
    lines = requirement_lines(ROOT / 'requirements.txt', version, leave_out={COMPILED_HERE})
    resolved = resolve(lines, version, tmp_path, source_wheels,
                       constraints=[ROOT / 'requirements-lock.txt'])
    unpinned = {name: data['version'] for name, data in resolved.items()
                if lock.get(name, top.get(name)) != data['version']}
    assert not unpinned, f'Python {version} would install these without a pin: {unpinned}'
    metadata, file_name = resolve_compiled_here(top[COMPILED_HERE], version, tmp_path)
    assert metadata['version'] == top[COMPILED_HERE]
    assert not metadata.get('requires_dist'), 'it would need packages nothing pins'
    tag = f'cp{version.replace(".", "")}'
    assert tag in file_name or file_name.endswith('.tar.gz'), file_name
    assert normalized(metadata['name']) == COMPILED_HERE
