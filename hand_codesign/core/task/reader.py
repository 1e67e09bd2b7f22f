"""
Reading a task file: YAML text to a validated Task.

Each mistake is one TaskError naming the file, the dotted key, what was expected and what
came. The keys are declared once, on the fields of the Task and its parts (core.task.schema;
docs/TASK.md lists them), and read by ValueReader.section (core.task.values); what no kind of
value reads is a method here (the task's own values) or in core.task.settings_reader (the
search's), a seed design in core.task.design_reader. Rules across keys are in
core.task.checks.
"""

import dataclasses
import os
from typing import Union

from hand_codesign.core.task.checks import check_task
from hand_codesign.core.task.design_reader import DesignReader
from hand_codesign.core.task.parts import (AXES, CONTACT_PARAMETERS, ContactSpec, ENGINES,
                                           GoalSpec, ParameterSpec, PhysicsSpec, TaskError)
from hand_codesign.core.task.settings_reader import SettingsReader
from hand_codesign.core.task.spec import Task
from hand_codesign.core.task.values import join_key
import yaml


def load_task(path: Union[str, 'os.PathLike[str]'], warn_old_names: bool = True) -> Task:
    """
    Read and validate a task file: return its Task (core.task.spec), a frozen value.

    Args:
        path: a YAML task file (its keys and their SI units: docs/TASK.md).
        warn_old_names: warn of a key's old name (False for a file that records a task, as a
            campaign's pinned copy does, rather than one the user edits).

    Returns:
        The Task, its lengths in m, angles in rad, times in s, masses in kg.

    Raises:
        TaskError: (a ValueError) one line naming the file, the dotted key and what was
            expected, for a file that cannot be read, is not UTF-8 or YAML, or breaks the
            schema.
    """
    try:
        with open(path, encoding='utf-8') as stream:
            text = stream.read()
    except OSError as error:
        raise TaskError(f'{path}: cannot read the task file ({error.strerror})') from None
    except UnicodeDecodeError as error:
        raise TaskError(f'{path}: expected a task file in UTF-8 text, got byte '
                        f'0x{error.object[error.start]:02x} at offset {error.start}') from None
    return parse_task(text, source=str(path), warn_old_names=warn_old_names)


def parse_task(text: str, source: str = '<task>', warn_old_names: bool = False) -> Task:
    """
    Validate YAML text into a Task (core.task.spec), as load_task does for a file.

    Args:
        text: the YAML of a task; the Task keeps it as `source_text`.
        source: what names it in errors (a path or 'run ID task'), also the folder a seed
            design's file is read from.
        warn_old_names: a key's old name (core.task.schema, Key.old) is read as its name,
            with a warning if True (a file the user edits; not a bag's record).

    Returns:
        The Task, as load_task returns it.

    Raises:
        TaskError: naming source, the dotted key and what was expected.
    """
    try:
        document = yaml.safe_load(text)
    except yaml.YAMLError as error:
        raise TaskError(f'{source}: not valid YAML: {_yaml_problem(error)}') from None
    reader = _Reader(source, warn_old_names)
    task = reader.task(document)
    task = dataclasses.replace(task, source=source, source_text=text)
    check_task(task)
    return task


def parse_design(document, source, key='design'):
    """Validate a Design mapping in the format of `seed_design`; TaskError names source, key."""
    return _Reader(source).design(document, key)


class _Reader(SettingsReader, DesignReader):
    """Walks the parsed YAML by the schema, with dotted paths for errors."""

    def task(self, document):
        values = self.section(Task, document, '', skip=('structure',))
        values['structure'] = self.hand_structure(document['hand'], values['hierarchy'])
        values['hand'] = self.hand_placement(values['hand'], document['hand'])
        return Task(**values)

    # ---- the palm's placement: fixed (the paper), or searched within bounds

    def hand_placement(self, hand, section):
        """Return the HandSpec with the searched ranges of its base position and yaw (if any)."""
        position = section.get('base_position')
        yaw = section.get('base_yaw')
        return dataclasses.replace(
            hand,
            base_position_bounds=self.placement(position, 'hand.base_position', 3)[1],
            base_yaw_bounds=None if yaw is None else self.placement(yaw, 'hand.base_yaw',
                                                                    0)[1])

    def base_position(self, spec, value, key):
        """Return the nominal base position: the fixed one, or the centre of the bounds."""
        return self.placement(value, key, 3)[0]

    def base_yaw(self, spec, value, key):
        """Return the nominal base yaw: the fixed one, or the centre of the bounds."""
        return self.placement(value, key, 0)[0]

    def placement(self, value, key, size):
        """
        Return (nominal, bounds or None) of a base position (size 3) or yaw (size 0).

        A fixed value is [x, y, z] (a yaw: a number) or {fixed: ...}; a searched one is
        {bounds: [[x lower, x upper], [y lower, y upper], [z lower, z upper]]} (a yaw:
        {bounds: [lower, upper]}), the nominal value the centre of the bounds.
        """
        angle = size == 0
        fixed = ('[x, y, z] or {fixed: [x, y, z]}' if size else 'a number or {fixed: v}')
        pairs = ('[[x lower, x upper], [y lower, y upper], [z lower, z upper]]' if size
                 else '[lower, upper]')
        if isinstance(value, dict):
            if len(value) != 1 or set(value) - {'fixed', 'bounds'}:
                self.fail(key, f'{fixed} or {{bounds: {pairs}}}', value)
            if 'fixed' in value:
                return self.placement(value['fixed'], join_key(key, 'fixed'), size)
            raw, bounds_key = value['bounds'], join_key(key, 'bounds')
            if size:
                if not isinstance(raw, list) or len(raw) != 3:
                    self.fail(bounds_key, f'three pairs {pairs}', raw)
                bounds = tuple(self.bounds(pair, f'{bounds_key}[{index}]')
                               for index, pair in enumerate(raw))
                return tuple(b.centre for b in bounds), bounds
            bounds = self.bounds(raw, bounds_key, angle=True)
            return bounds.centre, bounds
        if size:
            if not isinstance(value, list):
                self.fail(key, f'{fixed} or {{bounds: {pairs}}}', value)
            return self.vector(value, key, 3), None
        if isinstance(value, bool) or not isinstance(value, (int, float, str)):
            self.fail(key, f'{fixed} or {{bounds: {pairs}}}', value)
        return self.number(value, key, angle=angle), None

    def hand_structure(self, hand, hierarchy):
        """Return hand.structure, or the hierarchy's start where the file leaves it out."""
        if 'structure' in hand:
            return self.structure(hand['structure'], 'hand.structure')
        if hierarchy is None:
            self.fail('hand.structure', 'this key (joints per finger, e.g. [2, 2]) unless a '
                      'hierarchy gives the start', got=False)
        return hierarchy.start

    def box_size(self, spec, value, key):
        """Return a box's edge lengths: three numbers, or one for a cube."""
        return self.vector(value if isinstance(value, list) else [value] * 3, key, 3,
                           positive=True)

    def goals(self, spec, value, key):
        values = self.section(GoalSpec, value, key)
        if not values['position'] and not values['orientation']:
            self.fail(key, 'at least one position or orientation goal', got=False)
        return GoalSpec(**values)

    def goal_list(self, spec, value, key):
        kind = key.rpartition('.')[2]
        if not isinstance(value, list):
            self.fail(key, f'a list of {kind} goals (or [])', value)
        goals = []
        for index, item in enumerate(value):
            item_key = f'{key}[{index}]'
            goal = spec.section(**self.section(spec.section, item, item_key))
            if goals and goal.time <= goals[-1].time:
                self.fail(join_key(item_key, 'time'),
                          f"a time after the previous goal's {goals[-1].time}", item['time'])
            goals.append(goal)
        return tuple(goals)

    def goal_axes(self, spec, value, key):
        if not isinstance(value, list) or not value or any(
                axis not in AXES for axis in value) or len(set(value)) != len(value):
            self.fail(key, 'a non-empty list of distinct world axes from x, y, z, e.g. '
                      '[x, y]', value)
        return tuple(axis for axis in AXES if axis in value)

    def physics(self, spec, value, key):
        """Return the physics: one `engine`, or the list `engines` (engine: the list's first)."""
        values = self.section(PhysicsSpec, value, key)
        if values['engines'] is None:
            values['engines'] = ()  # PhysicsSpec makes it (engine,)
        elif 'engine' in value:
            self.fail(join_key(key, 'engine'), 'engine or engines, not both (engines: '
                      f'{list(values["engines"])} names every engine)', got=False)
        else:
            values['engine'] = values['engines'][0]
        return PhysicsSpec(**values)

    def engine_list(self, spec, value, key):
        """Return physics.engines: a non-empty list of distinct engines."""
        if (not isinstance(value, list) or not value or any(
                not isinstance(name, str) or name not in ENGINES for name in value)
                or len(set(value)) != len(value)):
            self.fail(key, f'a non-empty list of distinct engines of {", ".join(ENGINES)}, '
                      'e.g. [pybullet, mujoco]', value)
        return tuple(value)

    def contact_section(self, spec, value, key):
        """Return physics.contact: at least one range of CONTACT_PARAMETERS."""
        contact = ContactSpec(**self.section(ContactSpec, value, key))
        if not contact.ranges():
            self.fail(key, f'at least one of {", ".join(CONTACT_PARAMETERS)} (or no contact '
                      "key: the engines' own contact)", value)
        return contact

    def contact_range(self, spec, value, key):
        """Return a range of physics.contact: [lower, upper] within the Key's limits."""
        bounds = self.bounds(value, key, minimum=spec.minimum)
        if spec.positive and not bounds.lower > 0:
            self.fail(key, 'a pair [lower, upper] of positive numbers', value)
        if spec.interval:
            self.within(spec, bounds.upper, value, key)
        return bounds

    def axis_ranges(self, spec, value, key):
        """Return the Bounds of an offset along world x, y and z: {x: [l, u], y: ..., z: ...}."""
        section = self.mapping(value, key, required=('x', 'y', 'z'))
        return tuple(self.bounds(section[axis], join_key(key, axis)) for axis in 'xyz')

    def limits_setting(self, spec, value, key):
        """Return joint_limits: a parameter setting whose fixed value is a pair (per finger)."""
        if isinstance(value, dict) and set(value) == {'fixed'}:
            raw, fixed_key = value['fixed'], join_key(key, 'fixed')
            if isinstance(raw, list) and raw and isinstance(raw[0], list):
                return ParameterSpec('fixed', tuple(
                    self.bounds(pair, f'{fixed_key}[{index}]', angle=True)
                    for index, pair in enumerate(raw)))
            return ParameterSpec('fixed', (self.bounds(raw, fixed_key, angle=True),))
        return self.parameter(value, key, angle=True, allow_none=True)

    def keyframes(self, spec, value, key):
        """Return a pd policy's keyframe times: positive, strictly increasing."""
        times = self.items(value, key, 'times',
                           lambda time, time_key: self.number(time, time_key, positive=True))
        if any(b <= a for a, b in zip(times, times[1:])):
            self.fail(key, 'strictly increasing times', value)
        return times

    def seed_design_of(self, spec, value, key):
        return self.seed_design(value, key)


def _yaml_problem(error):
    """Return a YAML error as one line: what is wrong and where (PyYAML spreads it out)."""
    mark = getattr(error, 'problem_mark', None)
    problem = getattr(error, 'problem', None)
    if problem is None or mark is None:
        return ' '.join(str(error).split())
    return f'{problem} at line {mark.line + 1}, column {mark.column + 1}'
