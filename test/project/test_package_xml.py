"""
package.xml declares every third-party module the package imports, so that rosdep installs it.

On the colcon path `rosdep install` reads package.xml; a module the code imports but the file
does not declare is missing at the first run. ROS packages are declared by name, Python
packages by rosdep key (python3-<name>, python3-<name>-pip or python-<name>-pip, as rosdistro
names them), and the PyPI packages in the `pip only:` comment, which the README's
pip line installs.
"""

import ast
import importlib.metadata
import pathlib
import re
import sys
import xml.etree.ElementTree as ElementTree

ROOT = pathlib.Path(__file__).resolve().parents[2]
SOURCES = ['hand_codesign', 'launch']


def imported_top_modules():
    """Return {top-level module: a file importing it} of the package's absolute imports."""
    found = {}
    for folder in SOURCES:
        for path in sorted((ROOT / folder).rglob('*.py')):
            for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
                if isinstance(node, ast.Import):
                    names = [alias.name for alias in node.names]
                elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
                    names = [node.module]
                else:
                    continue
                for name in names:
                    found.setdefault(name.split('.')[0], path.relative_to(ROOT))
    return {module: path for module, path in found.items()
            if module not in sys.stdlib_module_names and module != 'hand_codesign'}


def declarations():
    """Return (exec_depend keys, PyPI names of the `pip only:` comment) of package.xml."""
    text = (ROOT / 'package.xml').read_text()
    keys = {element.text for element in ElementTree.fromstring(text).iter('exec_depend')}
    pip_only = re.search(r'<!-- pip only: ([^\n]*)', text).group(1).split()
    return keys, pip_only


def accepted_names(module):
    """Return the names under which package.xml may declare a module."""
    names = {module, f'python3-{module}'}
    for distribution in importlib.metadata.packages_distributions().get(module, []):
        name = distribution.lower()
        names |= {name, f'python3-{name}', f'python3-{name}-pip', f'python-{name}-pip'}
    return names


def test_every_imported_module_is_declared():
    keys, pip_only = declarations()
    missing = {module: str(path) for module, path in imported_top_modules().items()
               if not accepted_names(module) & (keys | set(pip_only))}
    assert not missing, f'imported but not declared in package.xml: {missing}'
