"""
Reading a task file: YAML text to a validated Task.

Each mistake is one TaskError naming the file, the dotted key, what was expected and what
came. The schema is documented in hand_codesign.core.task; cross-field rules are in
hand_codesign.core.task.checks. The reading is split by section: single values in
core.task.values (ValueReader, the base), the search's sections in core.task.settings_reader,
designs in core.task.design_reader; this module reads the task's own sections and puts the
Task together.
"""

import dataclasses

from hand_codesign.core.task.checks import check_task
from hand_codesign.core.task.design_reader import DesignReader
from hand_codesign.core.task.parts import (ALGORITHMS, AXES, DISTANCES, GoalSpec, HandSpec,
                                           MORPHOLOGY_PARAMETERS, MorphologySpec, ObjectSpec,
                                           OrientationGoal, ParameterSpec, POLICY_KINDS,
                                           PolicySpec, PositionGoal, RandomizationSpec, SHAPES,
                                           STARTS, SymmetrySpec, TaskError, TORQUE_MODES,
                                           TorquePenaltySpec)
from hand_codesign.core.task.settings_reader import SettingsReader
from hand_codesign.core.task.spec import Task
from hand_codesign.core.task.values import join_key
from hand_codesign.deprecation import warn_old_name
import yaml

# an old top-level key -> its name now (hand_codesign.deprecation): read under either name
OLD_KEYS = {'num_world_states': 'world_states'}


def load_task(path):
    """
    Read and validate a task file: return its Task (core.task.spec), a frozen value.

    path: a YAML task file (the schema and its SI units: hand_codesign.core.task). Raises
    TaskError (a ValueError) with one line naming the file, the dotted key and what was
    expected, for a file that cannot be read, is not UTF-8 or YAML, or breaks the schema.
    """
    try:
        with open(path, encoding='utf-8') as stream:
            text = stream.read()
    except OSError as error:
        raise TaskError(f'{path}: cannot read the task file ({error.strerror})') from None
    except UnicodeDecodeError as error:
        raise TaskError(f'{path}: expected a task file in UTF-8 text, got byte '
                        f'0x{error.object[error.start]:02x} at offset {error.start}') from None
    return parse_task(text, source=str(path), warn_old_names=True)


def parse_task(text, source='<task>', warn_old_names=False):
    """
    Validate YAML text into a Task (core.task.spec), as load_task does for a file.

    text: the YAML of a task; source: what names it in errors (a path or 'run ID task'),
    also the folder a seed design's file is read from. The Task keeps the text as
    `source_text`. An old key name (OLD_KEYS) is read as the new one, with a warning if
    warn_old_names (a file the user edits; not a bag's record). Raises TaskError naming source,
    the dotted key and what was expected.
    """
    try:
        document = yaml.safe_load(text)
    except yaml.YAMLError as error:
        raise TaskError(f'{source}: not valid YAML: {_yaml_problem(error)}') from None
    reader = _Reader(source)
    task = reader.task(renamed_keys(document, source, warn_old_names))
    task = dataclasses.replace(task, source=source, source_text=text)
    check_task(task)
    return task


def parse_design(document, source, key='design'):
    """Validate a Design mapping in the format of `seed_design`; TaskError names source, key."""
    return _Reader(source).design(document, key)


def renamed_keys(document, source, warn):
    """Return the document with each old top-level key (OLD_KEYS) under its new name."""
    if not isinstance(document, dict) or not set(OLD_KEYS) & set(document):
        return document
    document = dict(document)
    for old, new in OLD_KEYS.items():
        if old not in document:
            continue
        if new in document:
            raise TaskError(f'{source}: {old} and {new} are one setting given twice: keep {new}')
        if warn:
            warn_old_name(old, new, f'{source}: task key ')
        document[new] = document.pop(old)
    return document


class _Reader(SettingsReader, DesignReader):
    """Walks the parsed YAML, checking keys and types with dotted paths for errors."""

    def task(self, document):
        top = self.mapping(document, '', required=(
            'name', 'seed', 'time_step', 'duration', 'object', 'hand', 'goals',
            'randomization', 'world_states', 'morphology', 'policy', 'optimizer'),
            optional=('description', 'torque_penalty', 'early_termination', 'weights',
                      'hierarchy', 'seed_design', 'two_stage', 'physics', 'worlds'))
        hierarchy = (self.hierarchy(top['hierarchy'], 'hierarchy')
                     if top.get('hierarchy') is not None else None)
        hand, structure = self.hand(top['hand'], 'hand', hierarchy)
        optimizer = self.mapping(top['optimizer'], 'optimizer',
                                 required=('algorithm', 'iterations', 'population'),
                                 optional=('initial_sigma', 'restart_stagnation', 'archive'))
        seed_design = None
        if top.get('seed_design') is not None:
            seed_design = self.seed_design(top['seed_design'], 'seed_design')
        description = top.get('description', '')
        if not isinstance(description, str):
            self.fail('description', 'a string', description)
        duration = self.number(top['duration'], 'duration', positive=True)
        return Task(
            name=self.text(top['name'], 'name'),
            description=description,
            seed=self.integer(top['seed'], 'seed', minimum=0),
            time_step=self.number(top['time_step'], 'time_step', positive=True),
            duration=duration,
            object_spec=self.object_spec(top['object'], 'object'),
            hand=hand,
            structure=structure,
            goals=self.goals(top['goals'], 'goals'),
            randomization=self.randomization(top['randomization'], 'randomization'),
            num_world_states=self.integer(top['world_states'], 'world_states'),
            morphology=self.morphology(top['morphology'], 'morphology'),
            policy=self.policy(top['policy'], 'policy'),
            algorithm=self.choice(optimizer['algorithm'], 'optimizer.algorithm', ALGORITHMS),
            iterations=self.integer(optimizer['iterations'], 'optimizer.iterations'),
            population=self.integer(optimizer['population'], 'optimizer.population'),
            initial_sigma=self.number(optimizer.get('initial_sigma', 0.1),
                                      'optimizer.initial_sigma', positive=True),
            restart_stagnation=(self.integer(optimizer['restart_stagnation'],
                                             'optimizer.restart_stagnation')
                                if optimizer.get('restart_stagnation') is not None else None),
            archive=(self.archive(optimizer['archive'], 'optimizer.archive')
                     if optimizer.get('archive') is not None else None),
            weights=self.weights(top.get('weights', {}), 'weights'),
            physics=self.physics(top.get('physics', {}), 'physics'),
            worlds=self.worlds(top.get('worlds', {}), 'worlds'),
            torque_penalty=self.torque_penalty(top.get('torque_penalty'), 'torque_penalty'),
            early_termination=self.early_termination(top.get('early_termination'),
                                                     'early_termination'),
            hierarchy=hierarchy,
            seed_design=seed_design,
            two_stage=self.boolean(top.get('two_stage', False), 'two_stage'))

    def object_spec(self, value, key):
        section = self.mapping(value, key, required=(
            'shape', 'mass', 'friction', 'start', 'position', 'orientation'),
            optional=('size', 'radius', 'length'))
        shape = self.choice(section['shape'], join_key(key, 'shape'), SHAPES)
        needed = {'sphere': ('radius',), 'box': ('size',), 'capsule': ('radius', 'length')}
        for name in ('size', 'radius', 'length'):
            if name in needed[shape] and name not in section:
                self.fail(join_key(key, name), f'this key for a {shape} (it is missing)',
                          got=False)
            if name not in needed[shape] and name in section:
                self.fail(join_key(key, name), f'no {name} for a {shape} (a sphere takes radius, '
                          'a box size, a capsule radius and length)', got=False)
        size = section.get('size')
        if size is not None:
            size = (self.vector([size] * 3, join_key(key, 'size'), 3, positive=True)
                    if not isinstance(size, list)
                    else self.vector(size, join_key(key, 'size'), 3, positive=True))
        return ObjectSpec(
            shape=shape,
            size=size,
            radius=(self.number(section['radius'], join_key(key, 'radius'), positive=True)
                    if 'radius' in section else None),
            length=(self.number(section['length'], join_key(key, 'length'), positive=True)
                    if 'length' in section else None),
            mass=self.number(section['mass'], join_key(key, 'mass'), positive=True),
            friction=self.number(section['friction'], join_key(key, 'friction'), minimum=0),
            start=self.choice(section['start'], join_key(key, 'start'), STARTS),
            position=self.vector(section['position'], join_key(key, 'position'), 3),
            orientation=self.quaternion(section['orientation'], join_key(key, 'orientation')))

    def hand(self, value, key, hierarchy):
        section = self.mapping(value, key, required=(
            'base_position', 'base_orientation', 'palm_size', 'segment_radius',
            'segment_density'), optional=('structure', 'palm_mass'))
        if 'structure' in section:
            structure = self.structure(section['structure'], join_key(key, 'structure'))
        elif hierarchy is not None:
            structure = hierarchy.start
        else:
            self.fail(join_key(key, 'structure'), 'this key (joints per finger, e.g. [2, 2]) '
                      'unless a hierarchy gives the start', got=False)
        spec = HandSpec(
            base_position=self.vector(section['base_position'], join_key(key, 'base_position'),
                                      3),
            base_orientation=self.quaternion(section['base_orientation'],
                                             join_key(key, 'base_orientation')),
            palm_size=self.vector(section['palm_size'], join_key(key, 'palm_size'), 3,
                                  positive=True),
            segment_radius=self.number(section['segment_radius'],
                                       join_key(key, 'segment_radius'), positive=True),
            segment_density=self.number(section['segment_density'],
                                        join_key(key, 'segment_density'), positive=True),
            palm_mass=self.number(section.get('palm_mass', 0.1), join_key(key, 'palm_mass'),
                                  positive=True))
        return spec, structure

    def goals(self, value, key):
        section = self.mapping(value, key, required=('distance', 'position', 'orientation'),
                               optional=('samples_per_second', 'relative_to_start',
                                         'orientation_symmetry'))
        position = self.goal_list(section['position'], join_key(key, 'position'), 'position')
        orientation = self.goal_list(section['orientation'], join_key(key, 'orientation'),
                                     'orientation')
        if not position and not orientation:
            self.fail(key, 'at least one position or orientation goal', got=False)
        return GoalSpec(
            distance=self.choice(section['distance'], join_key(key, 'distance'), DISTANCES),
            position=position, orientation=orientation,
            samples_per_second=self.number(section.get('samples_per_second', 10.0),
                                           join_key(key, 'samples_per_second'), positive=True),
            relative_to_start=self.boolean(section.get('relative_to_start', False),
                                           join_key(key, 'relative_to_start')),
            orientation_symmetry=self.symmetry(section.get('orientation_symmetry'),
                                               join_key(key, 'orientation_symmetry')))

    def symmetry(self, value, key):
        if value is None:
            return None
        section = self.mapping(value, key, required=('axis', 'order'))
        order = self.integer(section['order'], join_key(key, 'order'), minimum=2)
        return SymmetrySpec(axis=self.unit_vector(section['axis'], join_key(key, 'axis')),
                            order=order)

    def axes(self, value, key):
        if not isinstance(value, list) or not value or any(
                axis not in AXES for axis in value) or len(set(value)) != len(value):
            self.fail(key, 'a non-empty list of distinct world axes from x, y, z, e.g. '
                      '[x, y]', value)
        return tuple(axis for axis in AXES if axis in value)

    def goal_list(self, value, key, kind):
        if not isinstance(value, list):
            self.fail(key, f'a list of {kind} goals (or [])', value)
        goals = []
        for index, item in enumerate(value):
            item_key = f'{key}[{index}]'
            item = self.mapping(item, item_key, required=('time', kind, 'trajectory'),
                                optional=('axes',) if kind == 'position' else ())
            time = self.number(item['time'], join_key(item_key, 'time'), positive=True)
            if goals and time <= goals[-1].time:
                self.fail(join_key(item_key, 'time'),
                          f"a time after the previous goal's {goals[-1].time}", item['time'])
            trajectory = self.boolean(item['trajectory'], join_key(item_key, 'trajectory'))
            if kind == 'position':
                goals.append(PositionGoal(
                    time, self.vector(item[kind], join_key(item_key, kind), 3), trajectory,
                    self.axes(item.get('axes', list(AXES)), join_key(item_key, 'axes'))))
            else:
                goals.append(OrientationGoal(time, self.quaternion(item[kind],
                                                                   join_key(item_key, kind)),
                                             trajectory))
        return tuple(goals)

    def randomization(self, value, key):
        section = self.mapping(value, key, required=(
            'position', 'orientation', 'friction', 'scale', 'mass'))
        position_key = join_key(key, 'position')
        position = self.mapping(section['position'], position_key, required=('x', 'y', 'z'))
        orientation_key = join_key(key, 'orientation')
        orientation = self.mapping(section['orientation'], orientation_key,
                                   required=('axis', 'range'))
        scale = self.bounds(section['scale'], join_key(key, 'scale'))
        mass = self.bounds(section['mass'], join_key(key, 'mass'))
        for name, factor in (('scale', scale), ('mass', mass)):
            if not factor.lower > 0:
                self.fail(join_key(key, name), 'positive factors', section[name])
        return RandomizationSpec(
            position=tuple(self.bounds(position[axis], join_key(position_key, axis))
                           for axis in 'xyz'),
            orientation_axis=self.unit_vector(orientation['axis'],
                                              join_key(orientation_key, 'axis')),
            orientation=self.bounds(orientation['range'], join_key(orientation_key, 'range'),
                                    angle=True),
            friction=self.bounds(section['friction'], join_key(key, 'friction')),
            scale=scale, mass=mass)

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
            entries = value['bounds']
            if isinstance(entries, list) and entries and isinstance(entries[0], list):
                values = tuple(self.bounds(item, f'{entry_key}[{index}]', angle=angle,
                                           minimum=minimum)
                               for index, item in enumerate(entries))
            else:
                values = (self.bounds(entries, entry_key, angle=angle, minimum=minimum),)
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

    def morphology(self, value, key):
        section = self.mapping(value, key, required=MORPHOLOGY_PARAMETERS)

        def setting(name, **options):
            return self.parameter(section[name], join_key(key, name), **options)

        return MorphologySpec(
            initial_angle=setting('initial_angle', per_joint=True, angle=True),
            finger_position_x=setting('finger_position_x'),
            finger_position_z=setting('finger_position_z'),
            segment_length=setting('segment_length', per_joint=True, allow_total=True),
            axis_angle=setting('axis_angle', per_joint=True, angle=True),
            joint_limits=self.joint_limits(section['joint_limits'],
                                           join_key(key, 'joint_limits')),
            friction=setting('friction', minimum=0))

    def joint_limits(self, value, key):
        if isinstance(value, dict) and set(value) == {'fixed'}:
            # a fixed setting is a [lower, upper] pair, or one pair per finger
            raw, fixed_key = value['fixed'], join_key(key, 'fixed')
            if isinstance(raw, list) and raw and isinstance(raw[0], list):
                return ParameterSpec('fixed', tuple(
                    self.bounds(pair, f'{fixed_key}[{index}]', angle=True)
                    for index, pair in enumerate(raw)))
            return ParameterSpec('fixed', (self.bounds(raw, fixed_key, angle=True),))
        return self.parameter(value, key, angle=True, allow_none=True)

    def policy(self, value, key):
        kind = self.choice(value.get('kind') if isinstance(value, dict) else value,
                           join_key(key, 'kind'), POLICY_KINDS)
        common = ('kind', 'duration')
        if kind == 'torque':
            section = self.mapping(value, key, required=common + ('mode', 'knots', 'torque'),
                                   optional=('gravity_compensation',))
            return PolicySpec(
                kind=kind,
                duration=self.number(section['duration'], join_key(key, 'duration'),
                                     positive=True),
                gravity_compensation=self.boolean(section.get('gravity_compensation', False),
                                                  join_key(key, 'gravity_compensation')),
                mode=self.choice(section['mode'], join_key(key, 'mode'), TORQUE_MODES),
                knots=self.integer(section['knots'], join_key(key, 'knots')),
                torque=self.parameter(section['torque'], join_key(key, 'torque')))
        section = self.mapping(value, key, required=common + ('keyframe_times', 'target', 'kp',
                                                              'kd'),
                               optional=('gravity_compensation',))
        times_key = join_key(key, 'keyframe_times')
        times = self.items(section['keyframe_times'], times_key, 'times',
                           lambda time, time_key: self.number(time, time_key, positive=True))
        if any(b <= a for a, b in zip(times, times[1:])):
            self.fail(times_key, 'strictly increasing times', section['keyframe_times'])
        return PolicySpec(
            kind=kind,
            duration=self.number(section['duration'], join_key(key, 'duration'), positive=True),
            gravity_compensation=self.boolean(section.get('gravity_compensation', True),
                                              join_key(key, 'gravity_compensation')),
            keyframe_times=times,
            target=self.parameter(section['target'], join_key(key, 'target'), angle=True),
            kp=self.parameter(section['kp'], join_key(key, 'kp'), minimum=0),
            kd=self.parameter(section['kd'], join_key(key, 'kd'), minimum=0))

    def torque_penalty(self, value, key):
        if value is None:
            return None
        section = self.mapping(value, key, required=('threshold', 'weight'))
        weight = self.number(section['weight'], join_key(key, 'weight'), positive=True)
        if weight >= 1:
            self.fail(join_key(key, 'weight'), 'a weight w in (0, 1)', section['weight'])
        return TorquePenaltySpec(
            threshold=self.number(section['threshold'], join_key(key, 'threshold'), minimum=0),
            weight=weight)


def _yaml_problem(error):
    """Return a YAML error as one line: what is wrong and where (PyYAML spreads it out)."""
    mark = getattr(error, 'problem_mark', None)
    problem = getattr(error, 'problem', None)
    if problem is None or mark is None:
        return ' '.join(str(error).split())
    return f'{problem} at line {mark.line + 1}, column {mark.column + 1}'
