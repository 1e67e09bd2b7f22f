"""
Build PyBullet from its pinned source with profile-guided optimization; install it in .venv.

Why: 70 % of a rollout's time is Bullet's multibody constraint solver and 14 % its collision
detection (core/sim/pybullet_sim.py). The PyPI wheel is compiled once for every machine; compiled
here again, instrumented, run on a co-design workload and compiled once more with that profile
(GCC's -fprofile-generate / -fprofile-use), the same source steps 1.1 to 1.25 times as fast
on Task 5's scene (the ratio varies from run to run on a shared machine). The objectives stay
bit-identical: profile-guided optimization lays out and inlines code by measured branch
frequencies, it never reorders floating-point arithmetic (no -ffast-math, no -march: the same
SSE2 instructions as the wheel).
`python bench/bench_pybullet_build.py` measures both claims against the wheel in one run.

Steps (about 10 minutes on 2 idle cores, once; the result is cached, see CACHE):
1. download the sdist of the very PyBullet version pinned in requirements.txt from PyPI and
   check its SHA-256;
2. build it instrumented, run `tools/physics_workload.py` with it (Tasks 5, 6 and 1: boxes,
   a capsule, torque and PD control; a few seconds), build it again with the profile;
3. keep the wheel's extension module beside the venv (WHEEL_COPY, for the benchmark) and put
   the built one in its place.

If any step fails (no compiler, no network) the wheel stays and one line says why: a slower
physics engine, never a broken set-up. `make setup` keeps the wheel; `make fast-physics` runs
this build; `python tools/build_pybullet.py --restore` puts the wheel's module back.

Usage: python tools/build_pybullet.py [--restore]  (run by `make fast-physics` with .venv's python)
"""

import argparse
import hashlib
import importlib.metadata
import os
import pathlib
import shutil
import subprocess
import sys
import sysconfig
import tarfile
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[1]
SDIST_SHA256 = {
    '3.2.7': '042879db8d101ac7590dee475fc6aded508b85fe1273fdbbfde1d88bd200e14f',
}
RECIPE = 2  # bump when the flags or the workload change: the cache key changes with it
# -g0: no debug information (a 9 MB module instead of 140 MB). The others let Bullet's calls
# into its own functions go straight there instead of through the PLT (nothing interposes
# them in an extension module): about 4 % faster again, arithmetic untouched.
COMMON_FLAGS = '-g0 -fno-semantic-interposition -fno-plt -Wl,-Bsymbolic'
GENERATE_FLAGS = '-fprofile-generate={profile} -fprofile-update=single'
USE_FLAGS = '-fprofile-use={profile} -fprofile-correction -Wno-missing-profile'
WORKLOAD = ROOT / 'tools' / 'physics_workload.py'
CACHE = pathlib.Path(os.environ.get('XDG_CACHE_HOME', pathlib.Path.home() / '.cache')) \
    / 'hand_codesign' / 'pybullet'


class BuildError(RuntimeError):
    """A step of the build failed; the message says which and where its log is."""


def module_name():
    """Return the file name of PyBullet's extension module for this interpreter."""
    return 'pybullet' + sysconfig.get_config_var('EXT_SUFFIX')


def installed_module():
    """Return the path of the extension module installed in this interpreter's site-packages."""
    return pathlib.Path(sysconfig.get_paths()['platlib']) / module_name()


def wheel_copy(version=None):
    """Return where the wheel's own module is kept once the built one replaces it."""
    version = version or importlib.metadata.version('pybullet')
    return pathlib.Path(sys.prefix) / 'lib' / f'pybullet-wheel-{version}' / module_name()


def compiler_version():
    """Return the C++ compiler's version line (part of the cache key)."""
    result = subprocess.run(['c++', '--version'], capture_output=True, text=True, check=True)
    return result.stdout.splitlines()[0]


def cache_key(version):
    """Return the name under which a build of `version` is cached."""
    text = f'{version} {SDIST_SHA256[version]} {sys.version} {compiler_version()} {RECIPE}'
    return f'{version}-{hashlib.sha256(text.encode()).hexdigest()[:16]}'


def run_logged(command, log, cwd, env=None, what=''):
    """Run a command with its output appended to `log`; BuildError if it fails."""
    with open(log, 'a', encoding='utf-8') as stream:
        stream.write(f'\n$ {" ".join(map(str, command))}\n')
        stream.flush()
        result = subprocess.run(command, cwd=cwd, stdout=stream, stderr=subprocess.STDOUT,
                                env=env)
    if result.returncode:
        raise BuildError(f'{what} failed (exit {result.returncode}); see {log}')


def fetch_sdist(version, folder, log):
    """Download the sdist of `version` into `folder`, check its hash; return its path."""
    if version not in SDIST_SHA256:
        raise BuildError(f'pybullet {version}: no pinned source hash in tools/build_pybullet.py '
                         f'(known: {", ".join(SDIST_SHA256)})')
    run_logged([sys.executable, '-m', 'pip', 'download', f'pybullet=={version}',
                '--no-binary', ':all:', '--no-deps', '--quiet', '-d', str(folder)],
               log, folder, what='downloading the pybullet sdist')
    sdist = folder / f'pybullet-{version}.tar.gz'
    digest = hashlib.sha256(sdist.read_bytes()).hexdigest()
    if digest != SDIST_SHA256[version]:
        raise BuildError(f'{sdist.name}: SHA-256 {digest}, expected {SDIST_SHA256[version]}')
    return sdist


def build(source, flags, log):
    """Compile the whole extension from `source` with extra compiler flags; return the module."""
    env = dict(os.environ, CFLAGS=f'{COMMON_FLAGS} {flags}', CXXFLAGS=f'{COMMON_FLAGS} {flags}',
               LDFLAGS=flags)
    run_logged([sys.executable, 'setup.py', 'build_ext', '--force'], log, source, env,
               what='compiling pybullet')
    built = list((source / 'build').glob(f'lib*/{module_name()}'))
    if not built:
        raise BuildError(f'compiling pybullet made no {module_name()}; see {log}')
    return built[0]


def train(module, log):
    """Run the co-design workload with the instrumented module (it writes the profile)."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(module.parent)] + [path for path in [os.environ.get('PYTHONPATH')] if path]))
    run_logged([sys.executable, str(WORKLOAD)], log, ROOT, env,
               what='running the profile workload')


def build_optimized(version, work, log):
    """Return the path of a profile-optimized module of `version` built under `work`."""
    sdist = fetch_sdist(version, work, log)
    with tarfile.open(sdist) as archive:
        archive.extractall(work, filter='data')
    source = work / f'pybullet-{version}'
    profile = work / 'profile'
    profile.mkdir()
    print('[setup] PyBullet: compiling it instrumented (1 of 2)', flush=True)
    train(build(source, GENERATE_FLAGS.format(profile=profile), log), log)
    print('[setup] PyBullet: compiling it with the measured profile (2 of 2)', flush=True)
    return build(source, USE_FLAGS.format(profile=profile), log)


def install(module):
    """Put `module` in place of the installed one, keeping the wheel's copy once."""
    target, keep = installed_module(), wheel_copy()
    if not keep.exists():
        keep.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(target, keep)
    temporary = target.with_suffix('.new')
    shutil.copy2(module, temporary)
    os.replace(temporary, target)  # a running process keeps the old file


def restore():
    """Put the wheel's module back."""
    if wheel_copy().exists():
        shutil.copy2(wheel_copy(), installed_module())
        print(f"[setup] PyBullet: the wheel's module is back in {installed_module()}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--restore', action='store_true', help="put the wheel's module back")
    arguments = parser.parse_args()
    if arguments.restore:
        restore()
        return 0
    version = importlib.metadata.version('pybullet')
    try:
        cached = CACHE / cache_key(version) / module_name()
        if not cached.exists():
            print(f'[setup] PyBullet {version}: building it from source with profile-guided '
                  'optimization (about 10 minutes on 2 cores, once, then cached)', flush=True)
            with tempfile.TemporaryDirectory(prefix='pybullet-build-') as folder:
                work = pathlib.Path(folder)
                log = ROOT / 'build' / 'pybullet-build.log'
                log.parent.mkdir(exist_ok=True)
                log.write_text('')
                module = build_optimized(version, work, log)
                cached.parent.mkdir(parents=True, exist_ok=True)
                shutil.copy2(module, cached.with_suffix('.tmp'))
                os.replace(cached.with_suffix('.tmp'), cached)
        install(cached)
        print(f'[setup] PyBullet {version}: using the profile-optimized build ({cached})')
    except (BuildError, OSError, subprocess.SubprocessError) as error:
        print(f'[setup] PyBullet: keeping the wheel, the faster build failed: {error}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
