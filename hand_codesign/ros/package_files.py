"""
The package's own files: its share/ folder, and the task files named relative to it.

A parameter file names a task as `config/tasks/task5.yaml`; started outside the repository
(`ros2 launch`, `ros2 run` from any folder) that path is found in the installed share/.
"""

import pathlib

from ament_index_python.packages import get_package_share_directory
from ament_index_python.packages import PackageNotFoundError
from hand_codesign.errors import UserError

PACKAGE = 'hand_codesign'
# a development install (`make setup`, pip -e) registers no share/; its source tree holds the
# same config/ at the same relative paths
SOURCE_TREE = pathlib.Path(__file__).resolve().parents[2]


def share_folder():
    """Return the package's share/ folder (colcon's install), else its source tree."""
    try:
        return pathlib.Path(get_package_share_directory(PACKAGE))
    except PackageNotFoundError:
        return SOURCE_TREE


def package_file(path, what):
    """
    Return the file `path` names: as given, or a relative one under the package's share/.

    what: the parameter or option that named it, for the one line raised (UserError) when
    neither place holds it; an absolute or empty path is returned as given.
    """
    if not str(path):
        return path
    given = pathlib.Path(path).expanduser()
    if given.is_absolute() or given.exists():
        return given
    installed = share_folder() / given
    if installed.exists():
        return installed
    raise UserError(f'{what} {path}: no such file in the working folder {pathlib.Path.cwd()} '
                    f'nor in the package share/ {share_folder()}')
