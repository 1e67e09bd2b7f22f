"""
The same arithmetic on every x86-64 processor: numpy's SIMD kernels and OpenBLAS's, pinned.

numpy and its OpenBLAS choose their kernels when numpy is imported, by the processor they find,
and the kernels round differently in the last bits, which contact and forty generations of a
search carry into other designs. Measured on an AMD EPYC with AVX-512 (issue 49), forcing each
choice by hand:

- numpy's ufuncs on processors with AVX-512 (its dispatch target X86_V4, SVML) give other last
  bits than on AVX2 processors (X86_V3) for tan, exp, log, expm1, log1p, exp2, log2, log10,
  cbrt, sinh, cosh, arcsinh, arcsin, arccos, arctan, arctanh, arctan2 and power (sin, cos,
  sqrt, hypot and sums agree); evaluate() reads them in building worlds and scoring, so a
  PyBullet evaluation of the bit-for-bit test (test_evaluate.py) changes;
- OpenBLAS's kernels (SkylakeX on AVX-512 processors, Haswell or Zen on AVX2 ones) give other
  last bits in matrix products, dot products and eigendecompositions: pycma's CMA-ES and
  pyribs's emitters (CMA-MAE, CMA-ME) follow other paths; DEAP's MO-CMA-ES did not change.

MuJoCo, PyBullet, glibc's libm (its FMA routines on every processor with AVX2) and the L2 size
or thread count OpenBLAS is given changed nothing. So every process of hand_codesign pins both
before numpy is imported (the package's __init__ calls `pin`, and a run hands the same
variables to its processes): numpy dispatches no further than X86_V3 and OpenBLAS runs its
Haswell kernels, which is what an AVX2 processor does by itself. Any x86-64 processor with
AVX2 and FMA (Intel since 2013, AMD since 2017) then computes the same; results are those an
AVX2 processor gave before the pin, and on an AVX-512 processor they change. A processor
without AVX2 or FMA is left as it is (its results differ), and
HAND_CODESIGN_NATIVE_ARITHMETIC=1 leaves any processor's own choice (the results of its kind).
"""

import os
import sys

# numpy 2.4's dispatch targets above X86_V3 (numpy._core._multiarray_umath.__cpu_dispatch__;
# test_arithmetic checks the list against the numpy installed)
NUMPY_TARGETS_OFF = ('X86_V4', 'AVX512_ICL', 'AVX512_SPR')
BLAS_CORE = 'Haswell'
NATIVE = 'HAND_CODESIGN_NATIVE_ARITHMETIC'
NEEDED_FLAGS = ('avx2', 'fma')
PINNED_VARIABLES = ('NPY_DISABLE_CPU_FEATURES', 'OPENBLAS_CORETYPE')
# their values before this process pinned them (None: unset), for a child that must compute
# as the processor itself does
BEFORE = {}


def processor_flags(path='/proc/cpuinfo'):
    """Return the set of this processor's flags (empty when they cannot be read)."""
    try:
        with open(path, encoding='ascii', errors='replace') as stream:
            for line in stream:
                if line.startswith('flags'):
                    return set(line.split(':', 1)[1].split())
    except OSError:
        pass
    return set()


def pinned_variables(environment=None, flags=None):
    """
    Return the environment variables that pin the arithmetic ({} where it is not pinned).

    environment: the variables to judge (default os.environ); flags: the processor's flags
    (default processor_flags()).
    """
    environment = os.environ if environment is None else environment
    flags = processor_flags() if flags is None else flags
    if environment.get(NATIVE, '') not in ('', '0') or not set(NEEDED_FLAGS) <= flags:
        return {}
    return dict(zip(PINNED_VARIABLES, (' '.join(NUMPY_TARGETS_OFF), BLAS_CORE)))


def pin():
    """
    Pin the arithmetic of this process and of the processes it starts; return a status line.

    Call it before numpy is imported: numpy reads the variables once, when imported. With numpy
    already imported the variables still go to the processes started from here on.
    """
    variables = pinned_variables()
    BEFORE.update({name: os.environ.get(name) for name in PINNED_VARIABLES})
    os.environ.update(variables)
    if not variables:
        return ('native: ' + (f'{NATIVE} is set' if os.environ.get(NATIVE, '') not in ('', '0')
                              else 'this processor lacks AVX2 or FMA'))
    if 'numpy' in sys.modules:
        return 'not pinned in this process: numpy was imported before hand_codesign'
    return f'pinned: numpy up to X86_V3, OpenBLAS {BLAS_CORE} kernels'
