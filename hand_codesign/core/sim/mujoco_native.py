"""
Eq. (1)'s PD law stepped in C (mujoco_pd.c beside this file), with no Python per step.

MuJoCo's own inverse dynamics (mj_comVel, mj_rne) and the scene's kinematics of the step
(mj_step1) give the law's M(theta) a + C(theta, thetad) thetad_d, as the Python law of
core.sim.mujoco_sim.mujoco_torques does with the same calls and the same arithmetic: the two
give the same bits (test_mujoco_native checks it), so which one runs changes no result, only
the time (bench/bench_engines.py --tasks task1 task5_pd prints it).

The C source is compiled on first use with the system's C compiler (a requirement of
`make setup`, tools/check_system.sh) against the mujoco wheel's headers and library, without
floating-point contraction (an FMA would round differently from Python), and cached under
$XDG_CACHE_HOME/hand_codesign (default ~/.cache) by a key of the source, the flags, the
compiler and MuJoCo's version; a process writes it under a name of its own and renames it,
so evaluators starting together never load a half-written file. Without a compiler
`library()` returns None and the simulator steps the law in Python.
"""

import ctypes
import glob
import hashlib
import os
import pathlib
import subprocess
import tempfile

import mujoco
import numpy as np

SOURCE = pathlib.Path(__file__).with_name('mujoco_pd.c')
FLAGS = ('-O2', '-std=gnu99', '-fPIC', '-shared', '-ffp-contract=off', '-fno-fast-math')
CACHE = pathlib.Path(os.environ.get('XDG_CACHE_HOME', pathlib.Path.home() / '.cache')) \
    / 'hand_codesign'
COMPILER = os.environ.get('CC', 'cc')
_LOADED = {}  # 'library' -> the CDLL or None, 'reason' -> why None


class PDLaw(ctypes.Structure):
    """mujoco_pd.c's hc_pd_law: one PD policy's constants over one rollout."""

    _fields_ = [('joints', ctypes.c_int), ('num_steps', ctypes.c_int),
                ('gains', ctypes.c_void_p), ('targets', ctypes.c_void_p),
                ('target_velocities', ctypes.c_void_p)]


def _mujoco_paths():
    """Return (include folder, shared library) of the mujoco wheel this process imported."""
    package = pathlib.Path(mujoco.__file__).parent
    libraries = sorted(glob.glob(str(package / 'libmujoco.so*')))
    if not libraries:
        raise OSError(f'no libmujoco.so* beside {mujoco.__file__}')
    return package / 'include', pathlib.Path(libraries[-1])


def _compiler_version():
    done = subprocess.run([COMPILER, '--version'], capture_output=True, text=True, check=True)
    return done.stdout.splitlines()[0] if done.stdout else COMPILER


def _build(path, include, shared):
    """Compile the source into `path` (written under another name, then renamed)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, partial = tempfile.mkstemp(dir=path.parent, suffix='.so.part')
    os.close(handle)
    try:
        subprocess.run([COMPILER, *FLAGS, f'-I{include}', str(SOURCE), '-o', partial,
                        f'-L{shared.parent}', f'-l:{shared.name}',
                        f'-Wl,-rpath,{shared.parent}'],
                       capture_output=True, text=True, check=True)
        os.replace(partial, path)
    finally:
        if os.path.exists(partial):
            os.remove(partial)


def _load():
    include, shared = _mujoco_paths()
    key = hashlib.sha256(b'\0'.join([SOURCE.read_bytes(), ' '.join(FLAGS).encode(),
                                     _compiler_version().encode(),
                                     mujoco.__version__.encode()])).hexdigest()[:16]
    path = CACHE / f'mujoco_pd-{key}.so'
    if not path.exists():
        _build(path, include, shared)
    library = ctypes.CDLL(str(path))
    library.hc_pd_advance.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p,
                                      ctypes.POINTER(PDLaw), ctypes.c_int, ctypes.c_int]
    library.hc_pd_advance.restype = ctypes.c_int
    return library


def library():
    """Return the compiled law (a ctypes CDLL), or None if it cannot be built here."""
    if 'library' not in _LOADED:
        try:
            _LOADED['library'] = _load()
        except (OSError, subprocess.CalledProcessError) as error:
            detail = getattr(error, 'stderr', '') or str(error)
            _LOADED['library'], _LOADED['reason'] = None, detail.strip().splitlines()[-1:]
    return _LOADED['library']


def unavailable_reason():
    """Return why the compiled law is not used ('' when it is)."""
    library()
    return ' '.join(_LOADED.get('reason', []))


class NativePD:
    """One PD policy's law over a rollout of `num_steps` steps, ready for `advance`."""

    def __init__(self, policy, num_steps):
        """
        Lay out a core.sim.policies.PDPolicy's constants for the C law.

        `policy`'s joints are the scene's first qpos and dof entries; `num_steps`, the steps
        of the rollout, gives the law a row of targets (rad) and target speeds (rad/s) each.
        """
        # policy.track's rows as arrays: track turns these into lists for the Python law,
        # and turning lists back into arrays cost 1 % of an evaluation
        targets, velocities = policy.target_at(np.arange(num_steps) * policy.time_step)
        self.arrays = (np.ascontiguousarray(policy.step_gains(), dtype=np.float64),
                       np.ascontiguousarray(targets, dtype=np.float64),
                       np.ascontiguousarray(velocities, dtype=np.float64))
        gains, targets, velocities = self.arrays  # kept alive: the struct points into them
        self.law = PDLaw(policy.num_joints, num_steps, gains.ctypes.data, targets.ctypes.data,
                         velocities.ctypes.data)
        self._library = library()

    def advancer(self, m, d, scratch):
        """
        Return advance(done, stop): step the scene (MjModel `m`, MjData `d`) under the law, in C.

        advance steps from step `done` to `stop`, 0 <= done <= stop <= num_steps (else
        ValueError); `scratch` is an MjData of m's sizes for the law's inverse dynamics. The
        call's arguments are made once here: made at each call they cost twice the call.
        """
        step, law = self._library.hc_pd_advance, ctypes.byref(self.law)
        addresses = (m._address, d._address, scratch._address)

        def advance(done, stop):
            if step(*addresses, law, done, stop) != stop - done:
                raise ValueError(f'steps {done} to {stop}: expected steps within the '
                                 f'{self.law.num_steps} of the law')
        return advance
