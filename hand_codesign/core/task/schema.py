"""
The task file's schema, declared once: metadata on the fields of the task's dataclasses.

Every key a task file may hold is a field of a dataclass of core.task.parts or of the Task
(core.task.spec) declared with `key(...)`: what it means, its unit, its default, its bounds or
choices, and how its value is read. From that one declaration

- the reader (core.task.values.ValueReader.section) knows which keys a mapping allows and
  requires, reads each value with its checks and fills in the defaults;
- the preview (core.run.preview) lists every setting of a task by its dotted key (`settings`),
  and `hand-codesign check` names the ones a file sets away from their defaults;
- docs/TASK.md's table of keys is generated (core.task.document), and a test keeps it current.

A new key of a task file is one field here; only a rule that spans several keys (in
core.task.checks) or a value of a shape no kind below reads needs code of its own.

Kinds of value: number, integer, boolean, choice, text, vector (`size` numbers), quaternion
([x, y, z, w] or {axis, angle}), unit_vector, bounds ([lower, upper]), structure (joints per
finger), parameter (a parameter setting: fixed, bounds, delta or seed), section (a mapping read
by the schema of the dataclass `section`), and custom (read by the reader's method `read`).

A key that was renamed keeps its old name in `old`: the reader takes it for the new one, with
one line saying so (none for a bag's recorded task), and the docs name it.
"""

import dataclasses
from typing import Any, Optional, Tuple

import numpy as np

KINDS = ('number', 'integer', 'boolean', 'choice', 'text', 'vector', 'quaternion',
         'unit_vector', 'bounds', 'structure', 'parameter', 'section', 'custom')
SCHEMA = 'task_key'   # the metadata entry of a field that is a key of the task file


class _Required:
    """The default of a key that must be in the file."""

    def __repr__(self):
        return 'REQUIRED'


class _Given:
    """The default of a key that the reader gives from the keys around it (see default_text)."""

    def __repr__(self):
        return 'GIVEN'


REQUIRED = _Required()
GIVEN = _Given()


@dataclasses.dataclass(frozen=True)
class Depends:
    """A default that depends on another key of the same mapping: values[that key's value]."""

    on: str
    values: Tuple[Tuple[str, Any], ...]

    def value(self, section):
        """Return the default for a mapping whose key `on` holds section[on]."""
        return dict(self.values)[section[self.on]]


@dataclasses.dataclass(frozen=True)
class Key:
    """What a key of the task file means and how its value is read (see the module doc)."""

    meaning: str
    kind: str
    unit: str = ''
    default: Any = REQUIRED       # REQUIRED, GIVEN, a Depends, or the value when it is absent
    default_text: str = ''        # the default as the docs say it, when it is not one value
    choices: Tuple[str, ...] = ()
    minimum: Optional[float] = None
    positive: bool = False
    interval: str = ''            # e.g. '(0, 1]': the value must lie in it
    noun: str = 'a number'        # what the interval's message calls the value
    angle: bool = False           # an angle: the YAML may say pi, -pi/2, 2*pi/3
    size: int = 0                 # a vector's length
    yaml: str = ''                # its dotted path in the mapping when not the field's name
    section: Any = None           # the dataclass of a section's keys
    read: str = ''                # the reader's method for a custom value
    # (key, values, phrase): the key belongs in its mapping only when that key has one of the
    # values; phrase names the condition in messages, e.g. 'for a {}' (a box)
    when: Tuple[Any, ...] = ()
    listed: bool = False          # a section: a list of such mappings (goals)
    values: str = ''              # what values a custom key takes, as the docs say it
    per_joint: bool = False       # a parameter: a fixed value may be a list per joint
    total: bool = False           # a parameter: per_finger_total allowed (segment_length)
    none: bool = False            # a parameter: `none` allowed (joint_limits)
    # the key's old name in its mapping, still read as this key with one line naming the new
    # (hand_codesign.deprecation), so a file written before the rename keeps working
    old: str = ''

    @property
    def required(self):
        """Return whether the key must be in the file (where `when` lets it be there)."""
        return self.default is REQUIRED

    def interval_bounds(self):
        """Return (low, high, low open, high open) of `interval`."""
        low, high = self.interval[1:-1].split(',')
        return float(low), float(high), self.interval[0] == '(', self.interval[-1] == ')'


def key(meaning, kind, *, field_default=dataclasses.MISSING, **options):
    """
    Return a dataclass field that is a key of the task file.

    Args:
        meaning: what the key says, one phrase (the docs' and the preview's).
        kind: one of KINDS.
        field_default: the dataclass's default, when it is not the key's own `default`.
        **options: the other attributes of Key (unit, default, choices, minimum, ...).

    Returns:
        a dataclasses.field whose metadata holds the Key. A plain default (not REQUIRED,
        GIVEN or a Depends) is also the field's default unless field_default is given.
    """
    spec = Key(meaning, kind, **options)
    assert kind in KINDS, kind
    if field_default is dataclasses.MISSING and not isinstance(
            spec.default, (_Required, _Given, Depends)):
        field_default = spec.default
    return dataclasses.field(default=field_default, metadata={SCHEMA: spec})


@dataclasses.dataclass(frozen=True)
class Entry:
    """One key of a mapping: the field it fills, its path in the mapping, its Key."""

    field: str
    path: Tuple[str, ...]
    spec: Key


def entries(cls):
    """
    Return the Entries of the keys of a dataclass's mapping, in field order.

    Args:
        cls: a dataclass whose fields are declared with key(); fields without one (the Task's
            source, variant, ...) are not keys.

    Returns:
        list of Entry; a path has two names where the key sits in a mapping of the mapping
        (`optimizer.algorithm` of the Task).
    """
    found = []
    for field in dataclasses.fields(cls):
        spec = field.metadata.get(SCHEMA)
        if spec is not None:
            found.append(Entry(field.name, tuple((spec.yaml or field.name).split('.')), spec))
    return found


def applies(entry, switches):
    """Return whether an entry belongs in a mapping, given the values of its `when` keys."""
    if not entry.spec.when:
        return True
    name, values, _ = entry.spec.when
    return switches.get(name) in values


@dataclasses.dataclass(frozen=True)
class Row:
    """A key of the whole task file, for the docs: its dotted path and its Key."""

    path: str
    spec: Key


def rows(cls, prefix=''):
    """
    Return every key of a dataclass's mapping and of the mappings below, depth first.

    Args:
        cls: the Task (the whole file) or a dataclass of one of its sections.
        prefix: the dotted path of cls's mapping in the file.

    Returns:
        list of Row, a section's row before the rows of its keys.
    """
    found = []
    for entry in entries(cls):
        path = '.'.join(filter(None, (prefix,) + entry.path))
        found.append(Row(path, entry.spec))
        if entry.spec.section is not None:
            found.extend(rows(entry.spec.section, path + ('[]' if entry.spec.listed else '')))
    return found


def settings(value, prefix=''):
    """
    Return every setting of a task (or of a part of it) by dotted key, as plain values.

    Args:
        value: a Task, or a dataclass of one of its sections.
        prefix: the dotted path of value's mapping.

    Returns:
        dict of dotted key to its value as read (defaults filled in), in schema order; a
        section's keys stand under the section's path, a section that is absent is None.
    """
    found = {}
    for entry in entries(type(value)):
        path = '.'.join(filter(None, (prefix,) + entry.path))
        item = getattr(value, entry.field)
        if entry.spec.section is not None and dataclasses.is_dataclass(item):
            found.update(settings(item, path))
        else:
            found[path] = plain(item)
    return found


def plain(value):
    """Return a value of a task as JSON values: tuples as lists, dataclasses as mappings."""
    if dataclasses.is_dataclass(value):
        return {field.name: plain(getattr(value, field.name))
                for field in dataclasses.fields(value)}
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (tuple, list)):
        return [plain(item) for item in value]
    if isinstance(value, dict):
        return {name: plain(item) for name, item in value.items()}
    return value


def away_from_defaults(task_settings, cls):
    """
    Return the settings that differ from their keys' plain defaults.

    Args:
        task_settings: settings(task) of a Task.
        cls: the Task's class (its schema).

    Returns:
        dict of dotted key to value, of the keys with a default of one value (or one that
        depends on another key) whose value is another, in schema order; free text left out.
    """
    found = {}
    for row in rows(cls):
        default = row.spec.default
        if (row.path not in task_settings or row.spec.section is not None
                or row.spec.kind == 'text'):
            continue
        if isinstance(default, Depends):
            parent = row.path.rpartition('.')[0]
            default = dict(default.values).get(task_settings.get(f'{parent}.{default.on}'))
        elif isinstance(default, (_Required, _Given)) or default is None:
            continue
        if task_settings[row.path] != plain(default):
            found[row.path] = task_settings[row.path]
    return found
