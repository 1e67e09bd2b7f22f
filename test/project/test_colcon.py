"""
The ROS 2 path: a colcon workspace build of both packages, checked the way `ros2 run` looks.

`ros2 run hand_codesign optimizer` asks ament_index_python for the package prefix and runs
`<prefix>/lib/hand_codesign/optimizer`; the ros2 command itself is not packaged for pip, so
the test asks the same index the same question.
"""

import os
import pathlib
import subprocess
import sys

import pytest

pytestmark = pytest.mark.system

ROOT = pathlib.Path(__file__).resolve().parents[2]
EXECUTABLES = ['optimizer', 'evaluator', 'recorder', 'live_view', 'robot_view', 'codesign']


@pytest.fixture(scope='module')
def workspace(tmp_path_factory):
    base = tmp_path_factory.mktemp('colcon')
    venv = pathlib.Path(sys.prefix)
    env = dict(os.environ, AMENT_PREFIX_PATH=str(venv), CMAKE_PREFIX_PATH=str(venv))
    command = [
        str(venv / 'bin' / 'colcon'), '--log-base', str(base / 'log'), 'build',
        '--base-paths', str(ROOT), str(ROOT / 'msg_defs'),
        '--build-base', str(base / 'build'), '--install-base', str(base / 'install'),
        '--event-handlers', 'console_direct-',
        '--cmake-args', f'-DPython3_EXECUTABLE={sys.executable}', '-DBUILD_TESTING=OFF',
    ]
    result = subprocess.run(command, cwd=base, env=env, capture_output=True, text=True,
                            timeout=600)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    return base / 'install'


def installed_environment(install):
    """Return the environment a sourced workspace gives: its prefixes before the venv's."""
    prefixes = [install / 'hand_codesign', install / 'hand_codesign_msgs']
    site = f'lib/python{sys.version_info.major}.{sys.version_info.minor}/site-packages'
    return dict(
        os.environ,
        AMENT_PREFIX_PATH=os.pathsep.join([str(p) for p in prefixes] + [sys.prefix]),
        PYTHONPATH=os.pathsep.join(str(p / site) for p in prefixes),
        LD_LIBRARY_PATH=os.pathsep.join(
            [str(install / 'hand_codesign_msgs' / 'lib'), os.environ.get('LD_LIBRARY_PATH', '')]),
    )


def ask(install, code):
    result = subprocess.run([sys.executable, '-c', code], env=installed_environment(install),
                            capture_output=True, text=True, timeout=120, cwd='/')
    assert result.returncode == 0, result.stderr
    return result.stdout.strip()


def test_ros2_run_finds_every_executable(workspace):
    code = (
        'import os\n'
        'from ament_index_python.packages import get_package_prefix\n'
        'prefix = get_package_prefix("hand_codesign")\n'
        'print(prefix)\n'
        f'for name in {EXECUTABLES!r}:\n'
        '    path = os.path.join(prefix, "lib", "hand_codesign", name)\n'
        '    print(name, os.path.isfile(path) and os.access(path, os.X_OK))\n'
    )
    lines = ask(workspace, code).splitlines()
    assert lines[0] == str(workspace / 'hand_codesign')
    assert lines[1:] == [f'{name} True' for name in EXECUTABLES]


def test_package_share_holds_manifest_and_configs(workspace):
    share = workspace / 'hand_codesign' / 'share' / 'hand_codesign'
    assert (share / 'package.xml').is_file()
    marker = 'share/ament_index/resource_index/packages/hand_codesign'
    assert (workspace / 'hand_codesign' / marker).is_file()
    assert (share / 'config' / 'foxglove_layout.json').read_bytes() == (
        ROOT / 'config' / 'foxglove_layout.json').read_bytes()
    configs = {p.name for p in (ROOT / 'config' / 'tasks').glob('*.yaml')}
    assert configs and configs == {p.name for p in (share / 'config' / 'tasks').glob('*.yaml')}


def test_the_runs_dds_profile_is_installed_beside_the_runner(workspace):
    profile = ask(workspace, 'from hand_codesign.ros.discovery import START_PROFILE; '
                             'print(START_PROFILE.is_file(), START_PROFILE)')
    assert profile.startswith(f'True {workspace}'), profile


def test_messages_import_from_the_install(workspace):
    code = (
        'import hand_codesign_msgs.msg as m\n'
        'from rclpy.serialization import serialize_message, deserialize_message\n'
        'c = m.Candidate(run_id="r", candidate_id=7, genome=[0.5, 0.25])\n'
        'back = deserialize_message(serialize_message(c), m.Candidate)\n'
        'print(m.__file__)\n'
        'print(back.candidate_id, list(back.genome))\n'
    )
    module_file, decoded = ask(workspace, code).splitlines()
    assert module_file.startswith(str(workspace / 'hand_codesign_msgs'))
    assert decoded == '7 [0.5, 0.25]'


def test_installed_executable_runs(workspace):
    executable = workspace / 'hand_codesign' / 'lib' / 'hand_codesign' / 'codesign'
    result = subprocess.run([str(executable), '--help'], env=installed_environment(workspace),
                            capture_output=True, text=True, timeout=120, cwd='/')
    assert result.returncode == 0, result.stderr
    assert 'analyze' in result.stdout and 'run' in result.stdout


def test_the_launch_file_and_what_it_names_are_installed(workspace):
    share = workspace / 'hand_codesign' / 'share' / 'hand_codesign'
    assert (share / 'launch' / 'codesign.launch.py').is_file()
    for name in ('recorder', 'evaluator', 'optimizer', 'robot_view'):   # test_launch.py's
        assert (share / 'config' / f'{name}.yaml').is_file()


def test_a_relative_task_file_is_found_in_the_installed_share(workspace):
    # the optimizer's parameter file names config/tasks/task5.yaml; `ros2 launch` runs from
    # any folder (here /), where the installed share/ holds it
    share = workspace / 'hand_codesign' / 'share' / 'hand_codesign'
    found = ask(workspace, 'from hand_codesign.ros.package_files import package_file; '
                           'print(package_file("config/tasks/task5.yaml", "task_file"))')
    assert found == str(share / 'config' / 'tasks' / 'task5.yaml')
    optimizer = workspace / 'hand_codesign' / 'lib' / 'hand_codesign' / 'optimizer'
    result = subprocess.run([str(optimizer), '--ros-args', '-p', 'task_file:=tasks/nope.yaml'],
                            env=dict(installed_environment(workspace), ROS_DOMAIN_ID='151'),
                            capture_output=True, text=True, timeout=120, cwd='/')
    assert result.returncode == 2
    assert ('parameter task_file tasks/nope.yaml: no such file in the working folder / nor in '
            f'the package share/ {share}') in result.stderr
