"""
The same designs on any x86-64 processor with AVX2: numpy's and OpenBLAS's kernels pinned.

hand_codesign.arithmetic says what differs between processors and why the pin is what it is.
The fingerprints below are tools/run_fingerprints.py's, of real runs (every process of the
run pinned on its own). PINNED is what an AVX2 processor computes by itself, measured on an AMD
EPYC with AVX-512 made to compute as one (HAND_CODESIGN_NATIVE_ARITHMETIC=1 with numpy's
dispatch stopped at X86_V3 and OpenBLAS's Zen kernels, those of an AMD EPYC without AVX-512),
and equally by the pinned runs there; NATIVE_AVX512 is what that processor computed before the
pin, the same as these runs gave on main before it.
"""

import importlib.util
import os
import pathlib
import subprocess
import sys

from hand_codesign import arithmetic
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
PINNED = {
    'task5': 'a91eae220e3030b8ff1f839bcee65c389d6c3f87cf42a844800a42a8486a0edf',
    'task5-cma-mae': 'a697d9bed495955ec641be00701b3dbbbd24828a4a8d5beabd9935f7ea0e211a',
}
NATIVE_AVX512 = {
    'task5': '41fdca5c6f9d0c3c69474efde30c5dd0f1afa83395a46f7a7fcc6e4719275aab',
}
# what a processor's own environment may say (a workplace sets OPENBLAS_CORETYPE on some):
# kernels every AVX2 processor can run, but not the pinned ones
OTHER_KERNELS = {'OPENBLAS_CORETYPE': 'Sandybridge', 'NPY_DISABLE_CPU_FEATURES': ''}
PROBE = ('import hand_codesign, numpy, threadpoolctl\n'
         'from numpy._core._multiarray_umath import __cpu_features__ as found\n'
         'print(hand_codesign.ARITHMETIC)\n'
         'print(found["X86_V3"], found["X86_V4"], found.get("AVX512_ICL"))\n'
         'print(threadpoolctl.threadpool_info()[0]["architecture"])\n')
needs_avx2 = pytest.mark.skipif(not set(arithmetic.NEEDED_FLAGS) <= arithmetic.processor_flags(),
                                reason='this processor lacks AVX2 or FMA: nothing is pinned')


def fingerprints_tool():
    """Return tools/run_fingerprints.py as a module."""
    spec = importlib.util.spec_from_file_location('run_fingerprints',
                                                  ROOT / 'tools' / 'run_fingerprints.py')
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def probe(**environment):
    """Return what a fresh process that imports hand_codesign first computes with."""
    result = subprocess.run([sys.executable, '-c', PROBE], capture_output=True, text=True,
                            env=dict(os.environ, **environment), timeout=120, cwd='/')
    assert result.returncode == 0, result.stderr
    return result.stdout.splitlines()


@pytest.mark.system
def test_every_numpy_target_above_avx2_is_turned_off():
    code = ('from numpy._core._multiarray_umath import __cpu_dispatch__\n'
            'print(" ".join(__cpu_dispatch__))')
    result = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                            timeout=120, cwd='/')
    assert set(result.stdout.split()) - {'X86_V3'} == set(arithmetic.NUMPY_TARGETS_OFF)


@pytest.mark.system
@needs_avx2
def test_a_process_pins_its_kernels_whatever_its_environment_says():
    status, numpy_targets, blas = probe(**OTHER_KERNELS)
    assert status == 'pinned: numpy up to X86_V3, OpenBLAS Haswell kernels'
    assert numpy_targets == 'True False False'
    assert blas == 'Haswell'


@pytest.mark.system
def test_native_arithmetic_is_left_alone_when_asked_or_without_avx2():
    assert arithmetic.pinned_variables({arithmetic.NATIVE: '1'}, {'avx2', 'fma'}) == {}
    assert arithmetic.pinned_variables({}, {'avx', 'sse4_2'}) == {}
    assert arithmetic.pinned_variables({}, {'avx2', 'fma', 'avx512f'}) == {
        'NPY_DISABLE_CPU_FEATURES': 'X86_V4 AVX512_ICL AVX512_SPR',
        'OPENBLAS_CORETYPE': 'Haswell'}
    status = probe(**{arithmetic.NATIVE: '1'})[0]
    assert status == f'native: {arithmetic.NATIVE} is set'


@pytest.mark.system
@needs_avx2
@pytest.mark.parametrize('name', sorted(PINNED))
def test_a_short_run_gives_the_fingerprint_of_another_processor(name, tmp_path, monkeypatch):
    for variable, value in OTHER_KERNELS.items():
        monkeypatch.setenv(variable, value)
    line = fingerprints_tool().run(name, tmp_path)
    assert line.split()[1] == PINNED[name]


@pytest.mark.system
@pytest.mark.skipif('avx512f' not in arithmetic.processor_flags(),
                    reason='the native arithmetic of this processor is the pinned one')
def test_unpinned_this_processor_gives_its_own_designs(tmp_path, monkeypatch):
    monkeypatch.setenv(arithmetic.NATIVE, '1')
    for variable, value in arithmetic.BEFORE.items():   # as this machine's environment says
        if value is None:
            monkeypatch.delenv(variable, raising=False)
        else:
            monkeypatch.setenv(variable, value)
    found = fingerprints_tool().run('task5', tmp_path).split()[1]
    assert found != PINNED['task5']
    if not any(arithmetic.BEFORE.values()):   # the processor's own kernels, as before the pin
        assert found == NATIVE_AVX512['task5']
