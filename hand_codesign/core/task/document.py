"""
docs/TASK.md's table of keys, written from the schema (core.task.schema), never by hand.

`keys_table()` is one Markdown row per key of a task file, in the order of the Task and its
parts; `with_keys(text)` puts it between the markers of docs/TASK.md (`python
tools/task_doc.py` rewrites the file; a test fails when the file is not what it writes).
"""

from hand_codesign.core.task.schema import Depends, GIVEN, REQUIRED, rows
from hand_codesign.core.task.spec import Task

BEGIN = '<!-- keys: written by `python tools/task_doc.py` from the schema; do not edit -->'
END = '<!-- end of keys -->'
_KIND_TEXT = {'boolean': 'true or false', 'text': 'text',
              'quaternion': 'quaternion [x, y, z, w] or {axis, angle}',
              'unit_vector': '3 numbers, a direction', 'bounds': '[lower, upper]',
              'structure': 'joints per finger, e.g. [2, 2]',
              'parameter': '{fixed: v}, {bounds: [l, u]}, {delta: [l, u]} or seed',
              'section': 'a mapping'}


def keys_table():
    """
    Return the table of every key of a task file, as Markdown lines.

    Returns:
        list of str: the header, then one row per key (dotted path, meaning, unit, default,
        what values it takes).
    """
    lines = ['| key | meaning | unit | default | values |', '|---|---|---|---|---|']
    for row in rows(Task):
        spec = row.spec
        meaning = spec.meaning + (f' (old name `{spec.old}`: still read, with a warning)'
                                  if spec.old else '')
        lines.append(f'| `{row.path}` | {_cell(meaning)} | {spec.unit or "-"} | '
                     f'{_cell(default_text(spec))} | {_cell(values_text(spec))} |')
    return lines


def default_text(spec):
    """Return what a key's default is, as the table says it."""
    if spec.default_text:
        return spec.default_text + _only(spec)
    if isinstance(spec.default, Depends):
        return ', '.join(f'{value} with {spec.default.on}: {on}'
                         for on, value in spec.default.values)
    if spec.default is REQUIRED:
        if spec.when:
            name, values, phrase = spec.when
            return 'required ' + phrase.format(' or '.join(values))
        return 'required'
    if spec.default is GIVEN:
        return 'given by the reader'
    if spec.default is None:
        return 'none'
    if spec.default == {}:
        return 'the defaults of its keys'
    if isinstance(spec.default, bool):
        return str(spec.default).lower() + _only(spec)
    if isinstance(spec.default, tuple):
        return '[' + ', '.join(str(item) for item in spec.default) + ']' + _only(spec)
    return str(spec.default) + _only(spec)


def _only(spec):
    """Return where a key that has a default has a place at all ('' anywhere)."""
    if not spec.when:
        return ''
    _, values, phrase = spec.when
    return '; only ' + phrase.format(' or '.join(values))


def values_text(spec):
    """Return what values a key takes: its kind, bounds or choices."""
    if spec.values:
        text = spec.values
    elif spec.choices:
        text = 'one of ' + ', '.join(spec.choices)
    elif spec.kind == 'vector':
        text = f'{spec.size} numbers'
    elif spec.kind in ('number', 'integer'):
        text = 'a whole number' if spec.kind == 'integer' else 'a number'
        minimum = 1 if spec.kind == 'integer' and spec.minimum is None else spec.minimum
        if spec.interval:
            text += f' in {spec.interval}'
        elif spec.positive:
            text += ' > 0'
        elif minimum is not None:
            text += f' >= {minimum:g}'
    else:
        text = _KIND_TEXT.get(spec.kind, '')
    if spec.listed:
        text = 'a list of mappings'
    if spec.angle:
        text += '; pi, -pi/2, 2*pi/3 ... allowed'
    if spec.kind in ('vector', 'bounds') and spec.positive:
        text += ', each > 0'
    return text


def with_keys(text):
    """
    Return docs/TASK.md's text with the table between its markers written afresh.

    Args:
        text: the file's text, holding BEGIN and END on lines of their own.

    Returns:
        the text with everything between the markers replaced by keys_table().
    """
    head, _, rest = text.partition(BEGIN + '\n')
    _, _, tail = rest.partition(END)
    return head + BEGIN + '\n' + '\n'.join(keys_table()) + '\n' + END + tail


def _cell(text):
    """Return text fit for a table cell."""
    return text.replace('|', '\\|')
