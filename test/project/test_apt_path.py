"""
The apt path on Ubuntu 24.04: the README's rosdep and colcon lines, and the venv's pip set.

rosdep finds a workspace's packages with catkin_pkg's crawl, which stops at the first folder
holding a package.xml, as colcon's does: the README's lines name both packages' folders, and
these tests run both crawls on exactly the paths the README gives, in a workspace holding this
repository as src/hand_codesign. The pip set (requirements-apt.txt) goes into a venv that
sees apt's numpy 1.26.4, which apt's ROS 2 messages are built against: pip's resolver shows
that every package in it, and everything they pull in, accepts that numpy on Python 3.12.
"""

import pathlib
import re
import subprocess
import sys
import xml.etree.ElementTree as ElementTree

from catkin_pkg.packages import find_packages
from packaging.version import Version
from pip_resolution import (build_source_wheels, COMPILED_HERE, numpy_requirements, pins,
                            requirement_lines, resolve, resolve_compiled_here)
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
README = (ROOT / 'README.md').read_text()
APT_NUMPY = '1.26.4'      # Ubuntu 24.04's python3-numpy
APT_PYTHON = '3.12'       # Ubuntu 24.04's python3
PACKAGES = {'hand_codesign', 'hand_codesign_msgs'}
# pins of requirements-apt.txt that differ from requirements.txt's and the lock's, and why
OWN_PINS = {'numpy': "apt's", 'ribs': '0.9.0 on need numpy >= 2',
            'pandas': '3.1.1 needs numpy >= 2'}


def readme_paths(command, option):
    """Return the paths the README's `command` line gives after `option`, up to the next one."""
    line = next(line for line in README.splitlines() if line.startswith(command))
    words = line.split('#')[0].split()
    paths = []
    for word in words[words.index(option) + 1:]:
        if word.startswith('-'):
            break
        paths.append(word)
    return paths


@pytest.fixture
def workspace(tmp_path):
    """Return a workspace whose src/hand_codesign is this repository."""
    (tmp_path / 'src').mkdir()
    (tmp_path / 'src' / 'hand_codesign').symlink_to(ROOT)
    return tmp_path


def test_the_readmes_rosdep_line_finds_both_packages(workspace):
    paths = readme_paths('rosdep install', '--from-paths')
    assert paths == ['src/hand_codesign', 'src/hand_codesign/msg_defs']
    found = {}
    for path in paths:  # as rosdep does: catkin_pkg's crawl of each path
        found.update({package.name: package for package in
                      find_packages(str(workspace / path)).values()})
    assert set(found) == PACKAGES
    # so --ignore-src leaves the message package to the workspace, not to a rosdep key
    depends = {dependency.name for dependency in found['hand_codesign'].exec_depends}
    assert 'hand_codesign_msgs' in depends
    # what the line fixes: a crawl of src alone stops at the top package.xml
    alone = {package.name for package in find_packages(str(workspace / 'src')).values()}
    assert alone == {'hand_codesign'}


@pytest.mark.system
def test_the_readmes_colcon_line_finds_both_packages(workspace):
    paths = readme_paths('python -m colcon build', '--base-paths')
    assert paths == ['src/hand_codesign', 'src/hand_codesign/msg_defs']
    colcon = pathlib.Path(sys.executable).parent / 'colcon'
    result = subprocess.run([str(colcon), 'list', '--names-only', '--base-paths', *paths],
                            cwd=workspace, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert set(result.stdout.split()) == PACKAGES


def test_rosdep_meets_only_keys_apt_installs():
    """No -pip key: rosdep's pip installer is refused by 24.04's Python (PEP 668)."""
    keys = set()
    for manifest in [ROOT / 'package.xml', ROOT / 'msg_defs' / 'package.xml']:
        root = ElementTree.fromstring(manifest.read_text())
        keys |= {element.text for element in root
                 if element.tag.endswith('depend') and element.tag != 'member_of_group'}
    odd = {key for key in keys
           if key.endswith('-pip') or not re.fullmatch(r'[a-z0-9_]+|python3-[a-z0-9-]+', key)}
    assert not odd, f'keys rosdep would not install from apt: {sorted(odd)}'


def test_the_pip_set_pins_every_pip_only_package_as_requirements_txt_does():
    text = (ROOT / 'package.xml').read_text()
    pip_only = re.search(r'<!-- pip only: ([^\n]*)', text).group(1).split()
    own = pins(ROOT / 'requirements-apt.txt')
    assert set(pip_only) <= set(own), set(pip_only) - set(own)
    usual = {**pins(ROOT / 'requirements-lock.txt'), **pins(ROOT / 'requirements.txt')}
    differing = {name for name, version in own.items() if usual.get(name) != version}
    assert differing == set(OWN_PINS)
    assert 'pip install -r src/hand_codesign/requirements-apt.txt' in README


@pytest.mark.system
def test_every_package_of_the_pip_set_accepts_apts_numpy(tmp_path):
    wheels = build_source_wheels(tmp_path / 'wheels')
    lines = requirement_lines(ROOT / 'requirements-apt.txt', APT_PYTHON,
                              leave_out={COMPILED_HERE})
    resolved = resolve(lines, APT_PYTHON, tmp_path, wheels)
    own = pins(ROOT / 'requirements-apt.txt')
    assert resolved['numpy']['version'] == APT_NUMPY == own['numpy']
    unpinned = {name: data['version'] for name, data in resolved.items()
                if own.get(name) != data['version']}
    assert not unpinned, f'pulled in without a pin in requirements-apt.txt: {unpinned}'
    refusing = {name: [str(r) for r in numpy_requirements(data, APT_PYTHON)]
                for name, data in resolved.items()
                if not all(r.specifier.contains(Version(APT_NUMPY))
                           for r in numpy_requirements(data, APT_PYTHON))}
    assert not refusing, f"these need another numpy than apt's: {refusing}"
    metadata, file_name = resolve_compiled_here(own[COMPILED_HERE], APT_PYTHON, tmp_path)
    assert file_name.endswith('.tar.gz') and not metadata.get('requires_dist')
