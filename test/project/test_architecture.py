"""The rooms of the package and of core, and the arrows between them (docs/ARCHITECTURE.md)."""

import ast
import pathlib

import pytest

PACKAGE = pathlib.Path(__file__).resolve().parents[2] / 'hand_codesign'
# room -> modules it must never import (at any depth, also inside functions)
FORBIDDEN = {
    'core': ('rclpy', 'hand_codesign_msgs', 'hand_codesign.bag', 'hand_codesign.ros',
             'hand_codesign.analysis', 'hand_codesign.campaign', 'hand_codesign.commands',
             'hand_codesign.cli'),
    # the bag format, readable without ROS by any tool: above core, below ros and analysis
    'bag': ('rclpy', 'hand_codesign_msgs', 'hand_codesign.ros', 'hand_codesign.analysis',
            'hand_codesign.campaign', 'hand_codesign.commands', 'hand_codesign.cli'),
    'ros': ('hand_codesign.analysis', 'hand_codesign.campaign', 'hand_codesign.commands',
            'hand_codesign.cli'),
    'analysis': ('rclpy', 'hand_codesign.ros', 'hand_codesign.campaign',
                 'hand_codesign.commands', 'hand_codesign.cli'),
    # the experiments and their tables: above analysis, below the commands that run them
    'campaign': ('rclpy', 'hand_codesign_msgs', 'hand_codesign.ros', 'hand_codesign.commands',
                 'hand_codesign.cli'),
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


# core's rooms (docs/ARCHITECTURE.md): room -> what its modules may import of core besides
# their own room. The root's shared vocabulary (contract, design, rotations, outcomes) imports
# nothing of core's rooms.
VOCABULARY = ('hand_codesign.core.contract', 'hand_codesign.core.design',
              'hand_codesign.core.rotations', 'hand_codesign.core.outcomes')
CORE_ROOMS = {
    'vocabulary': VOCABULARY,
    'task': VOCABULARY,
    'sim': VOCABULARY + ('hand_codesign.core.task',),
    'search': VOCABULARY + ('hand_codesign.core.task', 'hand_codesign.core.sim',
                            'hand_codesign.core.evaluate'),
    'experiments': VOCABULARY + ('hand_codesign.core.task', 'hand_codesign.core.sim',
                                 'hand_codesign.core.evaluate'),
    'run': VOCABULARY + ('hand_codesign.core.task', 'hand_codesign.core.sim',
                         'hand_codesign.core.evaluate', 'hand_codesign.core.search',
                         'hand_codesign.core.experiments'),
    'rig': VOCABULARY + ('hand_codesign.core.task', 'hand_codesign.core.sim',
                         'hand_codesign.core.evaluate', 'hand_codesign.core.search',
                         'hand_codesign.core.experiments', 'hand_codesign.core.run'),
}


def core_room(module):
    """Return the room of a module of core ('vocabulary' for the root's shared names)."""
    parts = module.split('.')
    if module in VOCABULARY:
        return 'vocabulary'
    return parts[2] if len(parts) > 3 else None


def module_name(path):
    """Return the dotted name of a file of the package."""
    parts = list(path.relative_to(PACKAGE.parent).with_suffix('').parts)
    return '.'.join(parts[:-1] if parts[-1] == '__init__' else parts)


def package_imports():
    """Return {module: {module of the package it imports, at any depth of the file}}."""
    modules = {module_name(path): path for path in PACKAGE.rglob('*.py')}
    graph = {}
    for name, path in modules.items():
        targets = set()
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
                names = [f'{node.module}.{alias.name}' for alias in node.names]
                names = [full if full in modules else node.module for full in names]
            else:
                continue
            for target in names:
                while target and target not in modules:
                    target = target.rpartition('.')[0]
                if target and target != name:
                    targets.add(target)
        graph[name] = targets
    return graph


def circles(graph):
    """Return the strongly connected components of two or more modules (Tarjan)."""
    index, low, stack, found = {}, {}, [], []

    def visit(node):
        index[node] = low[node] = len(index)
        stack.append(node)
        for child in graph[node]:
            if child not in index:
                visit(child)
                low[node] = min(low[node], low[child])
            elif child in stack:
                low[node] = min(low[node], index[child])
        if low[node] == index[node]:
            component = []
            while not component or component[-1] != node:
                component.append(stack.pop())
            if len(component) > 1:
                found.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return found


def test_no_module_of_the_package_imports_itself_in_a_circle():
    assert circles(package_imports()) == []


def test_the_circle_finder_finds_a_circle():
    graph = {'a': {'b'}, 'b': {'c'}, 'c': {'a'}, 'd': {'a'}}
    assert circles(graph) == [['a', 'b', 'c']]


@pytest.mark.parametrize('room', sorted(CORE_ROOMS))
def test_core_rooms_import_only_the_rooms_below(room):
    allowed = CORE_ROOMS[room]
    wrong = [f'{module} imports {target}'
             for module, targets in sorted(package_imports().items())
             if module.startswith('hand_codesign.core.') and core_room(module) == room
             for target in sorted(targets)
             if target.startswith('hand_codesign.core.') and core_room(target) != room
             and not any(target == ok or target.startswith(ok + '.') for ok in allowed)]
    assert not wrong, '\n'.join(wrong)


def test_every_module_of_core_is_in_a_room_or_at_its_root():
    root = {'hand_codesign.core', 'hand_codesign.core.evaluate', *VOCABULARY}
    homeless = [module for module in package_imports()
                if module.startswith('hand_codesign.core') and module not in root
                and module.split('.')[2] not in CORE_ROOMS and module.count('.') == 2]
    assert not homeless, homeless


def test_the_task_room_never_imports_its_own_face():
    # the face (task/__init__.py) imports the room's modules; one of them importing the face
    # would load the room in a circle
    wrong = [module for module, targets in package_imports().items()
             if module.startswith('hand_codesign.core.task.')
             and 'hand_codesign.core.task' in targets]
    assert not wrong, wrong


def test_the_campaign_room_never_imports_its_faces():
    # campaign/__init__.py names the room's modules; experiments/__init__.py imports every
    # experiment's module and orders them: a module below importing either would be a circle
    faces = ('hand_codesign.campaign', 'hand_codesign.campaign.experiments')
    wrong = [f'{module} imports {target}' for module, targets in package_imports().items()
             if module.startswith('hand_codesign.campaign.') and module not in faces
             for target in targets if target in faces]
    assert not wrong, wrong


def test_an_experiment_module_imports_no_other_experiment():
    # so a lever added to one experiment's module changes that experiment and no other
    prefix = 'hand_codesign.campaign.experiments.'
    wrong = [f'{module} imports {target}' for module, targets in package_imports().items()
             if module.startswith(prefix)
             for target in targets if target.startswith(prefix)]
    assert not wrong, wrong


def test_the_tests_mirror_the_package():
    # test/<room>/ and test/core/<room>/ name rooms of the package; project/ holds the tests of
    # the package as a whole (architecture, linters, packaging) and helpers/ what tests share
    tests = PACKAGE.parent / 'test'
    folders = {path.parent.relative_to(tests) for path in tests.rglob('test_*.py')}
    wrong = [str(folder) for folder in sorted(folders)
             if str(folder) not in ('.', 'project', 'helpers')
             and not (PACKAGE / folder).is_dir()]
    assert not wrong, f'test folders that name no room of hand_codesign: {wrong}'
    assert pathlib.Path('.') not in folders, 'a test file directly in test/: move it to its room'
