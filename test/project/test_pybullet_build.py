"""The PyBullet `make fast-physics` builds with profile-guided optimization: as the wheel."""

import json
import os
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / 'tools'))

import build_pybullet  # noqa: E402, I100: a tool script, not a package

pytestmark = pytest.mark.system

# `make fast-physics` leaves this stamp; `make setup` alone keeps the PyPI wheel
BUILT = (ROOT / '.venv' / '.stamps' / 'physics').exists()


@pytest.mark.skipif(not BUILT, reason='set up with the wheel: `make fast-physics` not run')
def test_setup_installed_the_build_and_it_evaluates_as_the_wheel(tmp_path):
    installed, wheel = build_pybullet.installed_module(), build_pybullet.wheel_copy()
    assert wheel.exists(), f'make fast-physics kept no copy of the wheel at {wheel}'
    assert installed.read_bytes() != wheel.read_bytes(), 'the installed PyBullet is the wheel'
    genomes = tmp_path / 'genomes.npy'
    subprocess.run([sys.executable, '-c', (
        'import sys, numpy as np; sys.path.insert(0, "bench"); '
        'from bench_core import candidates; '
        'from hand_codesign.core.task import load_task; '
        f'np.save("{genomes}", candidates(load_task("config/tasks/task5.yaml"), 3, seed=5))')],
        cwd=ROOT, check=True)
    bench = ROOT / 'bench' / 'bench_pybullet_build.py'
    results = [json.loads(subprocess.run(
        [sys.executable, str(bench), '--worker', str(genomes), '--rounds', '1'],
        env=dict(os.environ, PYTHONPATH=os.pathsep.join(
            [str(ROOT / 'bench')] + ([str(folder)] if folder else []))),
        cwd=ROOT, check=True, capture_output=True, text=True).stdout.splitlines()[-1])
        for folder in (wheel.parent, None)]
    assert [pathlib.Path(result['module']) for result in results] == [wheel, installed]
    assert results[0]['objectives'] == results[1]['objectives']
