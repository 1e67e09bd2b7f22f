"""
Point the CMake files exported by the ROS 2 wheels at this interpreter.

The wheels are built under /opt/python/cpXY-cpXY (cp311, cp312, cp313: the wheel for this
interpreter's version), and their exported CMake targets name that interpreter's include
folders. Any interface package that depends on another message package fails to configure
until these paths name the Python and numpy headers of this environment. Run it with the
environment's own python; it is idempotent.
"""

import pathlib
import sys
import sysconfig

import numpy

TAG = f'cp{sys.version_info.major}{sys.version_info.minor}'
BUILT_WITH = f'/opt/python/{TAG}-{TAG}'


def replacements():
    """Return (old, new) include paths, the numpy one first as it is the longer."""
    python_version = f'python{sys.version_info.major}.{sys.version_info.minor}'
    return [
        (f'{BUILT_WITH}/lib/{python_version}/site-packages/numpy/_core/include',
         numpy.get_include()),
        (f'{BUILT_WITH}/include/{python_version}', sysconfig.get_paths()['include']),
    ]


def rewrite(prefix):
    """Rewrite every exported .cmake file under prefix/share; return how many changed."""
    changed = 0
    for cmake_file in pathlib.Path(prefix, 'share').rglob('*.cmake'):
        text = cmake_file.read_text()
        if BUILT_WITH not in text:
            continue
        for old, new in replacements():
            text = text.replace(old, new)
        cmake_file.write_text(text)
        changed += 1
    return changed


if __name__ == '__main__':
    print(f'rewrote interpreter paths in {rewrite(sys.prefix)} CMake files')
