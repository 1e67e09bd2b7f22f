"""
Every test that starts a process is marked `system` (pytest.ini), so `-m "not system"` is quick.

Read from the tests' own code, without running them: a test starts a process when its body,
a fixture it takes, or a function it calls (in its file, in test/helpers or in another test
file it imports from), at any depth, calls subprocess, os.fork or os.system, multiprocessing,
rclpy.init, a launch service, runs the `hand-codesign` verbs that start processes
in-process (`main(['run', ...])`, not `reproduce --rates`), asks for a pool of processes
(`processes=2`) or loads a script of tools/ or bench/ (they run real runs). Such a test carries
`@pytest.mark.system`, or its file `pytestmark = pytest.mark.system`. A long physics run that
starts no process is marked by hand.
"""

import ast

from layout import TEST

# module -> the attributes of it whose call starts a process (None: any attribute)
STARTERS = {'subprocess': None, 'multiprocessing': None, 'rclpy': {'init'},
            'os': {'fork', 'system', 'posix_spawn', 'spawnv', 'execv'},
            'launch': {'LaunchService'}, 'launch_testing': None}
# verbs of `hand-codesign` that start processes when a test calls cli.main in-process, and
# the flags with which they only read (a campaign's folders)
PROCESS_VERBS = {'run', 'reproduce'}
READING_FLAGS = {'--list', '--rates', '--bands'}


def dotted(node):
    """Return 'a.b.c' of a Name or Attribute chain, else None."""
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if isinstance(node, ast.Name):
        return '.'.join([node.id] + parts[::-1])
    return None


def starts_by_itself(call, aliases):
    """Return whether a Call node starts a process directly (STARTERS, process verbs)."""
    name = dotted(call.func)
    if name is None:
        return False
    head, _, rest = name.partition('.')
    full = aliases.get(head, head) + ('.' + rest if rest else '')  # from subprocess import run
    module, _, attribute = full.partition('.')
    if module in STARTERS and attribute:
        allowed = STARTERS[module]
        return allowed is None or attribute.split('.')[-1] in allowed
    if any(keyword.arg == 'processes' and isinstance(keyword.value, ast.Constant)
           and isinstance(keyword.value.value, int) and keyword.value.value > 1
           for keyword in call.keywords):
        return True
    if name.split('.')[-1] in ('spec_from_file_location', 'run_path'):
        return any(isinstance(node, ast.Constant) and node.value in ('tools', 'bench')
                   for node in ast.walk(call))
    if name.split('.')[-1] == 'main' and call.args and isinstance(call.args[0], ast.List):
        words = [word.value for word in call.args[0].elts if isinstance(word, ast.Constant)]
        return bool(words) and words[0] in PROCESS_VERBS and not READING_FLAGS & set(words)
    return False


class Module:
    """What one file of test/ defines, imports and calls."""

    def __init__(self, path):
        self.path = path
        self.tree = ast.parse(path.read_text(), filename=str(path))
        self.aliases = {}   # local name -> module (import subprocess as sp)
        self.imported = {}  # local name -> (module stem, name) from another file of test/
        self.functions = {}  # name -> FunctionDef or ClassDef
        for node in self.tree.body:
            if isinstance(node, ast.Import):
                for alias in node.names:
                    if alias.asname:
                        self.aliases[alias.asname] = alias.name
                    else:  # import os.path binds os
                        self.aliases[alias.name.split('.')[0]] = alias.name.split('.')[0]
            elif isinstance(node, ast.ImportFrom) and node.module:
                for alias in node.names:
                    self.imported[alias.asname or alias.name] = (node.module, alias.name)
                    self.aliases[alias.asname or alias.name] = f'{node.module}.{alias.name}'
            elif isinstance(node, (ast.FunctionDef, ast.ClassDef)):
                self.functions[node.name] = node

    def system_file(self):
        """Return whether the file marks every test system (module-level pytestmark)."""
        for node in self.tree.body:
            if isinstance(node, ast.Assign) and any(
                    isinstance(target, ast.Name) and target.id == 'pytestmark'
                    for target in node.targets):
                return 'pytest.mark.system' in ast.unparse(node.value)
        return False


def marked_system(function):
    """Return whether a test function carries @pytest.mark.system."""
    return any(ast.unparse(decorator).startswith('pytest.mark.system')
               for decorator in function.decorator_list)


class Suite:
    """Every file of test/, and which of their functions start processes."""

    def __init__(self, root=TEST):
        self.modules = {path.stem: Module(path) for path in sorted(root.rglob('*.py'))}
        self.conftest = self.modules.get('conftest')
        self.memo = {}

    def resolve(self, module, name):
        """Return (module, definition) that `name` means in `module`, or None."""
        seen = set()
        while (module.path.stem, name) not in seen:
            seen.add((module.path.stem, name))
            if name in module.functions:
                return module, module.functions[name]
            if name in module.imported:
                stem, name = module.imported[name]
                if stem not in self.modules:
                    return None
                module = self.modules[stem]
            elif self.conftest is not None and module is not self.conftest:
                module = self.conftest
            else:
                return None
        return None

    def starts(self, module, definition):
        """Return whether a function (its body, its fixtures, what it calls) starts a process."""
        key = (module.path, definition.name)
        if key not in self.memo:
            self.memo[key] = False  # a cycle adds nothing
            self.memo[key] = self._starts(module, definition)
        return self.memo[key]

    def _starts(self, module, definition):
        names = set()
        if isinstance(definition, ast.FunctionDef):
            names |= {argument.arg for argument in definition.args.args}
        for node in ast.walk(definition):
            if isinstance(node, ast.Call):
                if starts_by_itself(node, module.aliases):
                    return True
                if isinstance(node.func, ast.Name):
                    names.add(node.func.id)
            elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Load):
                names.add(node.id)  # a function passed on (a callback, a fixture's helper)
        for name in names - {definition.name}:
            found = self.resolve(module, name)
            if found is not None and self.starts(*found):
                return True
        return False

    def unmarked(self):
        """Return 'file::test' of every process-starting test not marked system."""
        wrong = []
        for stem, module in self.modules.items():
            if not stem.startswith('test_') or module.system_file():
                continue
            for name, definition in module.functions.items():
                if (name.startswith('test_') and isinstance(definition, ast.FunctionDef)
                        and not marked_system(definition) and self.starts(module, definition)):
                    wrong.append(f'{module.path.relative_to(TEST)}::{name}')
        return wrong


def test_every_test_that_starts_a_process_is_marked_system():
    wrong = Suite().unmarked()
    assert not wrong, ('these tests start processes: mark them @pytest.mark.system (or the '
                       'file pytestmark = pytest.mark.system):\n' + '\n'.join(wrong))


def test_the_reading_finds_a_process_behind_a_fixture_and_a_helper(tmp_path):
    (tmp_path / 'helper_runs.py').write_text(
        'import subprocess as sp\nfrom os import fork\n\ndef launch_it():\n'
        '    sp.run(["true"])\n\ndef split():\n    fork()\n')
    (tmp_path / 'test_sample.py').write_text(
        'import pytest\nfrom helper_runs import launch_it\n\n'
        '@pytest.fixture\ndef started():\n    launch_it()\n\n'
        'def test_uses_fixture(started):\n    pass\n\n'
        'def test_pure():\n    assert 1 + 1 == 2\n\n'
        'def test_pool():\n    evaluate_all(processes=2)\n\n'
        'def test_forks():\n    split()\n\n'
        '@pytest.mark.system\ndef test_marked(started):\n    pass\n')
    suite = Suite(tmp_path)
    module = suite.modules['test_sample']
    assert suite.starts(module, module.functions['test_uses_fixture'])
    assert not suite.starts(module, module.functions['test_pure'])
    assert suite.starts(module, module.functions['test_pool'])
    assert not suite.starts(module, module.functions['test_forks'])  # not imported here
    helper = suite.modules['helper_runs']
    assert suite.starts(helper, helper.functions['split'])
    assert suite.starts(module, module.functions['test_marked'])
