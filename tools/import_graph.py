"""
Count the import structure of a package: modules, arrows, floors and circles.

An arrow is one module importing another module of the same package, at any depth of the file
(imports inside functions count: they hide circles rather than remove them). ``from pkg import
name`` points at ``pkg.name`` when that is a module, else at ``pkg`` itself. A circle is a
strongly connected component of two or more modules. Floors are the levels of the longest import
chain once every circle is folded into one node (a module that imports nothing of the package is
on floor 1).

Usage: python tools/import_graph.py [PACKAGE_DIR] [--within DOTTED.PREFIX] [--list]
(defaults: hand_codesign, the whole package). ``--within`` counts only the modules under a
prefix, e.g. ``hand_codesign.core``; ``--list`` prints every arrow and every circle.
"""

import argparse
import ast
import pathlib
import sys


def module_names(root):
    """Map each dotted module name of the package under ``root`` to its file."""
    modules = {}
    for path in sorted(root.rglob('*.py')):
        parts = list(path.relative_to(root.parent).with_suffix('').parts)
        if parts[-1] == '__init__':
            parts.pop()
        modules['.'.join(parts)] = path
    return modules


def resolve(module, path, node):
    """Return the absolute dotted name an ``ast.ImportFrom`` refers to."""
    if not node.level:
        return node.module
    package = module if path.name == '__init__.py' else module.rpartition('.')[0]
    for _ in range(node.level - 1):
        package = package.rpartition('.')[0]
    return f'{package}.{node.module}' if node.module else package


def imports_of(module, path, modules):
    """Yield every module of the package that ``module`` imports."""
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = resolve(module, path, node)
            targets = [f'{base}.{alias.name}' if f'{base}.{alias.name}' in modules else base
                       for alias in node.names]
        else:
            continue
        for target in targets:
            while target and target not in modules:
                target = target.rpartition('.')[0]
            if target and target != module:
                yield target


def circles(graph):
    """Return the strongly connected components of two or more modules (Tarjan, iterative)."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(sorted(component))
    return found


def floors(graph, components):
    """Return the number of levels of the longest import chain, circles folded."""
    group = {module: module for module in graph}
    for component in components:
        for module in component:
            group[module] = component[0]
    folded = {}
    for module, targets in graph.items():
        folded.setdefault(group[module], set()).update(
            group[target] for target in targets if group[target] != group[module])
    level = {}

    def height(node):
        if node not in level:
            level[node] = 1 + max((height(child) for child in folded[node]), default=0)
        return level[node]

    sys.setrecursionlimit(10000)
    return max((height(node) for node in folded), default=0)


def main():
    """Print the counts of one package, or of the modules under a prefix of it."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('package', nargs='?', default='hand_codesign')
    parser.add_argument('--within', default='', help='count only modules under this prefix')
    parser.add_argument('--list', action='store_true', help='print every arrow and circle')
    args = parser.parse_args()
    modules = module_names(pathlib.Path(args.package).resolve())
    inside = {name: path for name, path in modules.items()
              if not args.within or name == args.within or name.startswith(args.within + '.')}
    graph = {name: {target for target in imports_of(name, path, modules) if target in inside}
             for name, path in inside.items()}
    found = circles(graph)
    arrows = sum(len(targets) for targets in graph.values())
    print(f'{args.within or args.package}: modules {len(graph)}, arrows {arrows}, '
          f'floors {floors(graph, found)}, circles {len(found)}')
    if args.list:
        for name in sorted(graph):
            for target in sorted(graph[name]):
                print(f'  {name} -> {target}')
        for component in found:
            print('  circle: ' + ' '.join(component))


if __name__ == '__main__':
    main()
