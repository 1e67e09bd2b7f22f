"""
pip's own resolver, asked what a requirements file installs on another Python version.

`pip install --dry-run --report` resolves without installing; `--python-version` resolves for
an interpreter this machine need not have, and pip then takes wheels only. Three pinned
packages publish no wheel at all (SOURCE_ONLY, pure Python): they are built here once as
`py3-none-any` wheels, valid for any Python 3, and offered to the resolver. PyBullet publishes
wheels for Python 3.11 only; on 3.12 and 3.13 pip compiles its source (`make` has cmake and a
C++ compiler for that), so it is resolved from its source distribution on its own: it has no
dependencies, so it cannot clash with the rest.
"""

import json
import pathlib
import re
import subprocess
import sys

from packaging.markers import default_environment
from packaging.requirements import Requirement
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
SOURCE_ONLY = ('empy', 'flake8-blind-except', 'flake8-quotes')
COMPILED_HERE = 'pybullet'
OFFLINE = ('Failed to establish a new connection', 'Network is unreachable',
           'Temporary failure in name resolution', 'Max retries exceeded', 'timed out')
PIP = [sys.executable, '-m', 'pip', '--disable-pip-version-check', '--timeout', '30',
       '--retries', '2']


def normalized(name):
    """Return a distribution name as pip compares it (PEP 503)."""
    return re.sub(r'[-_.]+', '-', name).lower()


def target(python_version):
    """Return the marker environment of a plain install on python_version (e.g. '3.12')."""
    return dict(default_environment(), python_version=python_version,
                python_full_version=f'{python_version}.0', extra='')


def pins(path, python_version='3.12'):
    """Return {normalized name: version} of a requirements file's pins for python_version."""
    found = {}
    for line in pathlib.Path(path).read_text().splitlines():
        line = line.split('#')[0].strip()
        if '==' in line:
            requirement = Requirement(line)
            if requirement.marker is None or requirement.marker.evaluate(target(python_version)):
                found[normalized(requirement.name)] = str(requirement.specifier)[2:]
    return found


def pip(arguments, what):
    """Run pip; skip the test if the index cannot be reached, fail with pip's words else."""
    result = subprocess.run(PIP + arguments, capture_output=True, text=True, timeout=900)
    if result.returncode == 0:
        return result
    words = '\n'.join(line for line in (result.stdout + result.stderr).splitlines()
                      if 'is ignored' not in line)
    if any(sign in words for sign in OFFLINE):
        pytest.skip(f'the package index is unreachable from this machine ({what})')
    pytest.fail(f'{what}: pip says\n{words[-3000:]}')


def build_source_wheels(folder):
    """Build the pinned SOURCE_ONLY packages as pure wheels into folder; return it."""
    lock = pins(ROOT / 'requirements-lock.txt')
    wanted = [f'{name}=={lock[name]}' for name in SOURCE_ONLY]
    pip(['wheel', '--no-deps', '--quiet', '-w', str(folder), *wanted],
        'building the source-only packages')
    built = sorted(path.name for path in pathlib.Path(folder).glob('*.whl'))
    assert len(built) == len(SOURCE_ONLY) and all('-none-any' in name for name in built), built
    return folder


def resolve(requirements, python_version, folder, wheels, constraints=()):
    """
    Return {normalized name: metadata} of what pip would install from `requirements`.

    requirements: lines (pins); python_version: e.g. '3.12'; folder: for pip's files; wheels:
    a folder of extra wheels (build_source_wheels); constraints: constraint files.
    """
    folder = pathlib.Path(folder)
    source = folder / f'requirements-{python_version}.txt'
    source.write_text('\n'.join(requirements) + '\n')
    report = folder / f'report-{python_version}.json'
    arguments = ['install', '--dry-run', '--ignore-installed', '--quiet', '--report',
                 str(report), '--python-version', python_version, '--only-binary', ':all:',
                 '--find-links', str(wheels), '-r', str(source)]
    for constraint in constraints:
        arguments += ['-c', str(constraint)]
    pip(arguments, f'resolving for Python {python_version}')
    installs = json.loads(report.read_text())['install']
    return {normalized(item['metadata']['name']): item['metadata'] for item in installs}


def resolve_compiled_here(version, python_version, folder):
    """Return the metadata and file name pip would take for COMPILED_HERE==version."""
    report = pathlib.Path(folder) / f'{COMPILED_HERE}-{python_version}.json'
    pip(['install', '--dry-run', '--ignore-installed', '--no-deps', '--quiet', '--report',
         str(report), '--python-version', python_version, f'{COMPILED_HERE}=={version}'],
        f'resolving {COMPILED_HERE} for Python {python_version}')
    item = json.loads(report.read_text())['install'][0]
    return item['metadata'], item['download_info']['url'].rsplit('/', 1)[-1]


def requirement_lines(path, python_version, leave_out=()):
    """
    Return a file's requirements for python_version, their markers applied, as lines.

    pip judges a marker by the Python it runs on, not by --python-version: so the lines
    come without markers, those not for python_version and the names in leave_out left out.
    """
    lines = []
    for line in pathlib.Path(path).read_text().splitlines():
        line = line.split('#')[0].strip()
        if not line:
            continue
        requirement = Requirement(line)
        if normalized(requirement.name) in leave_out or not (
                requirement.marker is None
                or requirement.marker.evaluate(target(python_version))):
            continue
        requirement.marker = None
        lines.append(str(requirement))
    return lines


def numpy_requirements(metadata, python_version):
    """Return the numpy requirements a package states for a plain install on python_version."""
    environment = target(python_version)
    found = []
    for text in metadata.get('requires_dist', []):
        requirement = Requirement(text)
        if normalized(requirement.name) != 'numpy':
            continue
        if requirement.marker is None or requirement.marker.evaluate(environment):
            found.append(requirement)
    return found
