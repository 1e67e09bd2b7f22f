"""The rooms of the package and the arrows between them (docs/ARCHITECTURE.md)."""

import ast
import pathlib

import pytest

PACKAGE = pathlib.Path(__file__).resolve().parents[1] / 'hand_codesign'
# room -> modules it must never import (at any depth, also inside functions)
FORBIDDEN = {
    'core': ('rclpy', 'hand_codesign_msgs', 'hand_codesign.ros', 'hand_codesign.analysis',
             'hand_codesign.commands', 'hand_codesign.cli'),
    'ros': ('hand_codesign.analysis', 'hand_codesign.commands', 'hand_codesign.cli'),
    'analysis': ('rclpy', 'hand_codesign.ros', 'hand_codesign.commands', 'hand_codesign.cli'),
}
MAX_NODE_LINES = 150


def imported_modules(path):
    """Return every module a file imports, with the line of each import."""
    tree = ast.parse(path.read_text(), filename=str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, node.lineno
        elif isinstance(node, ast.ImportFrom) and node.module:
            yield node.module, node.lineno


@pytest.mark.parametrize('room', sorted(FORBIDDEN))
def test_imports_point_the_right_way(room):
    wrong = [f'{path.relative_to(PACKAGE.parent)}:{line} imports {module}'
             for path in sorted((PACKAGE / room).rglob('*.py'))
             for module, line in imported_modules(path)
             if any(module == bad or module.startswith(bad + '.') for bad in FORBIDDEN[room])]
    assert not wrong, '\n'.join(wrong)


def test_nodes_stay_thin():
    long = {path.name: len(path.read_text().splitlines())
            for path in (PACKAGE / 'ros').glob('*_node.py')}
    assert long and all(lines <= MAX_NODE_LINES for lines in long.values()), long
