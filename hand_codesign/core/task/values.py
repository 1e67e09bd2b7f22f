"""
Reading the values of a task file: numbers, vectors, bounds, quaternions, each checked.

`ValueReader` is the base of the task's readers (core.task.reader, core.task.settings_reader,
core.task.design_reader): each value comes with its dotted key, and a mistake is one TaskError
naming the file, the key, what was expected and what came. `section` reads a whole mapping by
the schema of its dataclass (core.task.schema): which keys it allows and requires, each value
by its kind and checks, the defaults of the keys it leaves out.
"""

import dataclasses
import math
import re

from hand_codesign.core.rotations import axis_angle_quaternion
from hand_codesign.core.task.parts import Bounds, ParameterSpec, TaskError
from hand_codesign.core.task.schema import applies, Depends, entries, GIVEN, REQUIRED
from hand_codesign.deprecation import warn_old_name
import numpy as np


class ValueReader:
    """Reads one value of the parsed YAML at a time, naming its dotted key in errors."""

    def __init__(self, source, warn_old_names=False):
        self.source = source
        # a file the user edits is told of an old key name; a bag's recorded task is not
        self.warn_old_names = warn_old_names

    def fail(self, key, expected, value=None, got=True):
        text = f'{self.source}: {key}: expected {expected}'
        if got:
            text += f', got {value!r}'
        raise TaskError(text)

    # ---- generic values

    def mapping(self, value, key, required=(), optional=()):
        if not isinstance(value, dict):
            self.fail(key or 'top level', 'a mapping', value)
        for name in value:
            if name not in required and name not in optional:
                allowed = ', '.join(list(required) + list(optional))
                self.fail(join_key(key, str(name)), f'no such key (allowed: {allowed})',
                          got=False)
        for name in required:
            if name not in value:
                self.fail(join_key(key, name), 'this key (it is missing)', got=False)
        return value

    def number(self, value, key, minimum=None, positive=False, angle=False):
        number = _angle_expression(value) if angle and isinstance(value, str) else value
        if isinstance(number, bool) or not isinstance(number, (int, float)) \
                or not math.isfinite(number):
            self.fail(key, 'a number', value)
        number = float(number)
        if positive and not number > 0:
            self.fail(key, 'a positive number', value)
        if minimum is not None and number < minimum:
            self.fail(key, f'a number >= {minimum}', value)
        return number

    def integer(self, value, key, minimum=1):
        if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
            what = 'a positive integer' if minimum == 1 else f'an integer >= {minimum}'
            self.fail(key, what, value)
        return int(value)

    def boolean(self, value, key):
        if not isinstance(value, bool):
            self.fail(key, 'true or false', value)
        return value

    def choice(self, value, key, choices):
        if value not in choices:
            self.fail(key, 'one of ' + ', '.join(choices), value)
        return value

    def text(self, value, key):
        if not isinstance(value, str) or not value.strip():
            self.fail(key, 'a non-empty string', value)
        return value

    def vector(self, value, key, size, positive=False, angle=False, minimum=None):
        if not isinstance(value, list) or len(value) != size:
            self.fail(key, f'a list of {size} numbers', value)
        return tuple(self.number(item, f'{key}[{index}]', positive=positive, angle=angle,
                                 minimum=minimum)
                     for index, item in enumerate(value))

    def bounds(self, value, key, angle=False, minimum=None):
        if not isinstance(value, list) or len(value) != 2:
            self.fail(key, 'a pair [lower, upper]', value)
        lower, upper = (self.number(item, f'{key}[{index}]', angle=angle, minimum=minimum)
                        for index, item in enumerate(value))
        if lower > upper:
            self.fail(key, 'lower <= upper', value)
        return Bounds(lower, upper)

    def quaternion(self, value, key):
        if isinstance(value, dict):
            self.mapping(value, key, required=('axis', 'angle'))
            axis = self.unit_vector(value['axis'], join_key(key, 'axis'))
            angle = self.number(value['angle'], join_key(key, 'angle'), angle=True)
            return axis_angle_quaternion(axis, angle)
        if not isinstance(value, list) or len(value) != 4:
            self.fail(key, 'a quaternion [x, y, z, w] or {axis: [x, y, z], angle: rad}',
                      value)
        return self._normalized(value, key, 4, 'quaternion')

    def unit_vector(self, value, key):
        return self._normalized(value, key, 3, 'vector')

    def _normalized(self, value, key, size, what):
        vector = np.array(self.vector(value, key, size))
        norm = np.linalg.norm(vector)
        if norm < 1e-9:
            self.fail(key, f'a non-zero {what}', value)
        return tuple(float(v) for v in vector / norm)

    def items(self, value, key, what, parse):
        """Return parse(item, 'key[index]') for each item of a non-empty list of `what`."""
        if not isinstance(value, list) or not value:
            self.fail(key, f'a non-empty list of {what}', value)
        return tuple(parse(item, f'{key}[{index}]') for index, item in enumerate(value))

    def structure(self, value, key):
        return self.items(value, key, 'joints per finger, e.g. [2, 2]', self.integer)

    # ---- sections, by the schema

    def section(self, cls, value, key, given=None, skip=(), extra=()):
        """
        Read a mapping by the schema of dataclass cls; return {field name: value}.

        Args:
            cls: the dataclass whose key() fields are the mapping's keys.
            value: the parsed YAML of the mapping.
            key: its dotted key ('' at the top level).
            given: {field: default} for keys whose default is GIVEN by the caller.
            skip: fields the caller reads itself (they stay allowed in the mapping).
            extra: (name, required) of keys the mapping also holds for its caller.

        Returns:
            a dict holding every field of the schema but those skipped; a key that does not
            apply (`when`) gets the field's dataclass default.
        """
        own = entries(cls)
        value = self.renamed(own, value, key)
        known = [entry.path[0] for entry in own] + [name for name, _ in extra]
        self.mapping(value, key, optional=list(dict.fromkeys(known)))   # no key unknown
        switches = self._switches(own, value, key)
        live = [entry for entry in own if applies(entry, switches)]
        self._not_applying(own, live, value, key, switches)
        self._keys(live, value, key, extra, switches)
        nested = {}   # keys of a section's mapping that belong to this mapping's dataclass
        for entry in live:
            if len(entry.path) == 2:
                nested.setdefault(entry.path[0], []).append((entry.path[1],
                                                             entry.spec.required))
        values = {}
        for entry in own:
            if entry.field in skip:
                continue
            if entry in live:
                values[entry.field] = self._entry(entry, value, key, switches, given or {},
                                                  nested.get(entry.path[0], ()))
            else:
                values[entry.field] = _field_default(cls, entry.field)
        return values

    def renamed(self, own, value, key):
        """Return the mapping with each key given by its old name (Key.old) under its name."""
        names = {entry.spec.old: entry.path[0] for entry in own if entry.spec.old}
        if not isinstance(value, dict) or not set(names) & set(value):
            return value
        value = dict(value)
        for old, new in names.items():
            if old not in value:
                continue
            if new in value:
                raise TaskError(f'{self.source}: {join_key(key, old)} and {join_key(key, new)} '
                                f'are one setting given twice: keep {new}')
            if self.warn_old_names:
                warn_old_name(join_key(key, old), join_key(key, new), f'{self.source}: task key ')
            value[new] = value.pop(old)
        return value

    def _switches(self, own, value, key):
        """Return {name: value read} of the keys other keys' `when` depends on."""
        names = {entry.spec.when[0] for entry in own if entry.spec.when}
        return {entry.path[0]: self._entry(entry, value, key, {}, {}, ())
                for entry in own if entry.path[0] in names}

    def _not_applying(self, own, live, value, key, switches):
        """Fail on a key the mapping holds although its `when` says it has no place there."""
        for entry in own:
            if entry not in live and entry.path[0] in value:
                name, allowed, phrase = entry.spec.when
                self.fail(join_key(key, entry.path[0]),
                          f'no {entry.path[0]} {phrase.format(switches[name])} (only '
                          f'{phrase.format(" or ".join(allowed))})', got=False)

    def _keys(self, live, value, key, extra, switches):
        """Check the keys of the mapping, and of the mappings its two-part paths go through."""
        required, optional = [], []
        for entry in live:
            name = entry.path[0]
            if entry.spec.required and entry.spec.when and name not in value:
                switch, _, phrase = entry.spec.when
                self.fail(join_key(key, name), f'this key {phrase.format(switches[switch])} '
                          '(it is missing)', got=False)
            if entry.spec.required and name not in required:
                required.append(name)
        for entry in live:
            if entry.path[0] not in required and entry.path[0] not in optional:
                optional.append(entry.path[0])
        for name, needed in extra:
            (required if needed else optional).append(name)
        self.mapping(value, key, required=required, optional=optional)
        inner = {}
        for entry in live:
            if len(entry.path) == 2 and entry.path[0] not in [e.path[0] for e in live
                                                              if len(e.path) == 1]:
                inner.setdefault(entry.path[0], []).append(entry)
        for name, group in inner.items():
            if name in value:
                self.mapping(value[name], join_key(key, name),
                             required=[e.path[1] for e in group if e.spec.required],
                             optional=[e.path[1] for e in group if not e.spec.required])

    def _entry(self, entry, value, key, switches, given, extra):
        """Return the value of one entry: read from the mapping, or its default."""
        spec, dotted = entry.spec, join_key(key, '.'.join(entry.path))
        raw = value
        for name in entry.path:
            raw = raw.get(name, _ABSENT) if isinstance(raw, dict) else _ABSENT
        if raw is _ABSENT or (raw is None and spec.default is None):
            if spec.default is REQUIRED:
                self.fail(dotted, 'this key (it is missing)', got=False)
            if spec.default is GIVEN:
                return given.get(entry.field)
            if isinstance(spec.default, Depends):
                return spec.default.value(switches)
            if spec.default is None:
                return None
            raw = list(spec.default) if isinstance(spec.default, tuple) else spec.default
        if extra and spec.kind == 'section' and len(entry.path) == 1:
            return spec.section(**self.section(spec.section, raw, dotted, extra=extra))
        return self.value(spec, raw, dotted)

    def value(self, spec, raw, key):
        """Return one value read by its Key's kind (core.task.schema.KINDS), checked."""
        kind = spec.kind
        if kind == 'section':
            return (getattr(self, spec.read)(spec, raw, key) if spec.read
                    else spec.section(**self.section(spec.section, raw, key)))
        if kind == 'custom':
            return getattr(self, spec.read)(spec, raw, key)
        if kind == 'number':
            number = self.number(raw, key, minimum=spec.minimum, positive=spec.positive,
                                 angle=spec.angle)
            return self.within(spec, number, raw, key) if spec.interval else number
        if kind == 'integer':
            return self.integer(raw, key, minimum=1 if spec.minimum is None else spec.minimum)
        if kind == 'bounds':
            bounds = self.bounds(raw, key, angle=spec.angle, minimum=spec.minimum)
            if spec.positive and not bounds.lower > 0:
                self.fail(key, 'positive factors', raw)
            return bounds
        if kind == 'parameter':
            return self.parameter(raw, key, per_joint=spec.per_joint, angle=spec.angle,
                                  minimum=spec.minimum, allow_total=spec.total,
                                  allow_none=spec.none)
        if kind == 'text':
            return self.text(raw, key) if spec.positive else self.string(raw, key)
        if kind == 'choice':
            return self.choice(raw, key, spec.choices)
        if kind == 'vector':
            return self.vector(raw, key, spec.size, positive=spec.positive, angle=spec.angle,
                               minimum=spec.minimum)
        return getattr(self, kind)(raw, key)   # boolean, quaternion, unit_vector, structure

    def within(self, spec, number, raw, key):
        """Return number if it lies in the Key's interval, else fail naming it."""
        low, high, low_open, high_open = spec.interval_bounds()
        if (number < low or (low_open and number == low) or number > high
                or (high_open and number == high)):
            self.fail(key, f'{spec.noun} in {spec.interval}', raw)
        return number

    def string(self, value, key):
        if not isinstance(value, str):
            self.fail(key, 'a string', value)
        return value

    # ---- parameter settings

    def parameter(self, value, key, per_joint=False, angle=False, minimum=None,
                  allow_total=False, allow_none=False):
        if value in ('seed', 'none'):
            if value == 'none' and not allow_none:
                self.fail(key, 'a setting {fixed: ...}, {bounds: ...}, {delta: ...} or seed',
                          value)
            return ParameterSpec(value)
        optional = ('per_finger_total',) if allow_total else ()
        if not isinstance(value, dict) or len(set(value) - set(optional)) != 1:
            self.fail(key, 'one of {fixed: v}, {bounds: [lower, upper]}, '
                      '{delta: [lower, upper]}, seed' + (', none' if allow_none else ''), value)
        self.mapping(value, key, optional=('fixed', 'bounds', 'delta') + optional)
        per_finger_total = self.boolean(value.get('per_finger_total', False),
                                        join_key(key, 'per_finger_total'))
        if 'delta' in value:
            return ParameterSpec('delta', (self.bounds(value['delta'], join_key(key, 'delta'),
                                                       angle=angle),))
        if 'bounds' in value:
            entry_key = join_key(key, 'bounds')
            entries_ = value['bounds']
            if isinstance(entries_, list) and entries_ and isinstance(entries_[0], list):
                values = tuple(self.bounds(item, f'{entry_key}[{index}]', angle=angle,
                                           minimum=minimum)
                               for index, item in enumerate(entries_))
            else:
                values = (self.bounds(entries_, entry_key, angle=angle, minimum=minimum),)
            return ParameterSpec('bounds', values, per_finger_total)
        if per_finger_total:
            self.fail(join_key(key, 'per_finger_total'), 'only with bounds', got=False)
        return ParameterSpec('fixed', self.fixed_values(value['fixed'], join_key(key, 'fixed'),
                                                        per_joint, angle, minimum))

    def fixed_values(self, value, key, per_joint, angle, minimum):
        def scalar(item, item_key):
            return self.number(item, item_key, angle=angle, minimum=minimum)

        if not isinstance(value, list):
            return (scalar(value, key),)
        if not value:
            self.fail(key, 'a value or a non-empty list per finger', value)
        values = []
        for index, item in enumerate(value):
            item_key = f'{key}[{index}]'
            if isinstance(item, list) and per_joint:
                values.append(tuple(scalar(v, f'{item_key}[{j}]') for j, v in enumerate(item)))
            else:
                values.append(scalar(item, item_key))
        return tuple(values)


_ABSENT = object()   # a key the mapping does not hold


def _field_default(cls, name):
    """Return the dataclass default of a field of cls."""
    return next(field.default for field in dataclasses.fields(cls) if field.name == name)


def join_key(prefix, name):
    """Return the dotted key of `name` under `prefix`."""
    return f'{prefix}.{name}' if prefix else name


_ANGLE = re.compile(r'^\s*(-)?\s*(?:(\d+(?:\.\d*)?)\s*\*\s*)?pi\s*(?:/\s*(\d+(?:\.\d*)?))?\s*$')


def _angle_expression(text):
    """Return the value of '[-][k*]pi[/d]' or the text itself when it is not one."""
    match = _ANGLE.match(text)
    if not match:
        return text
    sign, factor, divisor = match.groups()
    value = math.pi * float(factor or 1) / float(divisor or 1)
    return -value if sign else value
