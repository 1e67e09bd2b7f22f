"""
Reading a task file: YAML text to a validated Task.

Each mistake is one TaskError naming the file, the dotted key, what was expected and what
came. The schema is documented in hand_codesign.core.task; cross-field rules are in
hand_codesign.core.task.checks.
"""

import dataclasses
import math
import os
import re

from hand_codesign.core.design import (ControllerDesign, Design, FingerDesign, HandDesign,
                                       JointDesign)
from hand_codesign.core.rotations import axis_angle_quaternion
from hand_codesign.core.task.checks import check_task
from hand_codesign.core.task.parts import (ALGORITHMS, ARCHIVE_DESCRIPTOR_NAMES, ArchiveSpec, AXES,
                                           Bounds, DISTANCES, EarlyTerminationSpec, ENGINES,
                                           GoalSpec, HandSpec, HierarchySpec, HorizonSpec,
                                           MORPHOLOGY_PARAMETERS, MorphologySpec, ObjectSpec,
                                           OrientationGoal, ParameterSpec, PhysicsSpec,
                                           POLICY_KINDS, PolicySpec, PositionGoal,
                                           RandomizationSpec, SHAPES, STARTS, SymmetrySpec,
                                           TaskError, TORQUE_MODES, TorquePenaltySpec, WeightsSpec,
                                           WORLD_AGGREGATES, WORLD_RESAMPLING, WorldsSpec)
from hand_codesign.core.task.spec import Task
import numpy as np
import yaml


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
    return parse_task(text, source=str(path))


def parse_task(text, source='<task>'):
    """
    Validate YAML text into a Task (core.task.spec), as load_task does for a file.

    text: the YAML of a task; source: what names it in errors (a path or 'run ID task'),
    also the folder a seed design's file is read from. The Task keeps the text as
    `source_text`. Raises TaskError naming source, the dotted key and what was expected.
    """
    try:
        document = yaml.safe_load(text)
    except yaml.YAMLError as error:
        raise TaskError(f'{source}: not valid YAML: {_yaml_problem(error)}') from None
    reader = _Reader(source)
    task = reader.task(document)
    task = dataclasses.replace(task, source=source, source_text=text)
    check_task(task)
    return task


def parse_design(document, source, key='design'):
    """Validate a Design mapping in the format of `seed_design`; TaskError names source, key."""
    return _Reader(source).design(document, key)


class _Reader:
    """Walks the parsed YAML, checking keys and types with dotted paths for errors."""

    def __init__(self, source):
        self.source = source

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
                self.fail(_join(key, str(name)), f'no such key (allowed: {allowed})',
                          got=False)
        for name in required:
            if name not in value:
                self.fail(_join(key, name), 'this key (it is missing)', got=False)
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
            axis = self.unit_vector(value['axis'], _join(key, 'axis'))
            angle = self.number(value['angle'], _join(key, 'angle'), angle=True)
            return axis_angle_quaternion(axis, angle)
        if not isinstance(value, list) or len(value) != 4:
            self.fail(key, 'a quaternion [x, y, z, w] or {axis: [x, y, z], angle: rad}',
                      value)
        quaternion = np.array(self.vector(value, key, 4))
        norm = np.linalg.norm(quaternion)
        if norm < 1e-9:
            self.fail(key, 'a non-zero quaternion', value)
        return tuple(float(v) for v in quaternion / norm)

    def unit_vector(self, value, key):
        vector = np.array(self.vector(value, key, 3))
        norm = np.linalg.norm(vector)
        if norm < 1e-9:
            self.fail(key, 'a non-zero vector', value)
        return tuple(float(v) for v in vector / norm)

    def structure(self, value, key):
        if not isinstance(value, list) or not value:
            self.fail(key, 'a non-empty list of joints per finger, e.g. [2, 2]', value)
        return tuple(self.integer(item, f'{key}[{index}]') for index, item in enumerate(value))

    # ---- sections

    def task(self, document):
        top = self.mapping(document, '', required=(
            'name', 'seed', 'time_step', 'duration', 'object', 'hand', 'goals',
            'randomization', 'num_world_states', 'morphology', 'policy', 'optimizer'),
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
            num_world_states=self.integer(top['num_world_states'], 'num_world_states'),
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
        shape = self.choice(section['shape'], _join(key, 'shape'), SHAPES)
        needed = {'sphere': ('radius',), 'box': ('size',), 'capsule': ('radius', 'length')}
        for name in ('size', 'radius', 'length'):
            if name in needed[shape] and name not in section:
                self.fail(_join(key, name), f'this key for a {shape} (it is missing)', got=False)
            if name not in needed[shape] and name in section:
                self.fail(_join(key, name), f'no {name} for a {shape} (a sphere takes radius, '
                          'a box size, a capsule radius and length)', got=False)
        size = section.get('size')
        if size is not None:
            size = (self.vector([size] * 3, _join(key, 'size'), 3, positive=True)
                    if not isinstance(size, list)
                    else self.vector(size, _join(key, 'size'), 3, positive=True))
        return ObjectSpec(
            shape=shape,
            size=size,
            radius=(self.number(section['radius'], _join(key, 'radius'), positive=True)
                    if 'radius' in section else None),
            length=(self.number(section['length'], _join(key, 'length'), positive=True)
                    if 'length' in section else None),
            mass=self.number(section['mass'], _join(key, 'mass'), positive=True),
            friction=self.number(section['friction'], _join(key, 'friction'), minimum=0),
            start=self.choice(section['start'], _join(key, 'start'), STARTS),
            position=self.vector(section['position'], _join(key, 'position'), 3),
            orientation=self.quaternion(section['orientation'], _join(key, 'orientation')))

    def hand(self, value, key, hierarchy):
        section = self.mapping(value, key, required=(
            'base_position', 'base_orientation', 'palm_size', 'segment_radius',
            'segment_density'), optional=('structure', 'palm_mass'))
        if 'structure' in section:
            structure = self.structure(section['structure'], _join(key, 'structure'))
        elif hierarchy is not None:
            structure = hierarchy.start
        else:
            self.fail(_join(key, 'structure'), 'this key (joints per finger, e.g. [2, 2]) '
                      'unless a hierarchy gives the start', got=False)
        spec = HandSpec(
            base_position=self.vector(section['base_position'], _join(key, 'base_position'),
                                      3),
            base_orientation=self.quaternion(section['base_orientation'],
                                             _join(key, 'base_orientation')),
            palm_size=self.vector(section['palm_size'], _join(key, 'palm_size'), 3,
                                  positive=True),
            segment_radius=self.number(section['segment_radius'],
                                       _join(key, 'segment_radius'), positive=True),
            segment_density=self.number(section['segment_density'],
                                        _join(key, 'segment_density'), positive=True),
            palm_mass=self.number(section.get('palm_mass', 0.1), _join(key, 'palm_mass'),
                                  positive=True))
        return spec, structure

    def goals(self, value, key):
        section = self.mapping(value, key, required=('distance', 'position', 'orientation'),
                               optional=('samples_per_second', 'relative_to_start',
                                         'orientation_symmetry'))
        position = self.goal_list(section['position'], _join(key, 'position'), 'position')
        orientation = self.goal_list(section['orientation'], _join(key, 'orientation'),
                                     'orientation')
        if not position and not orientation:
            self.fail(key, 'at least one position or orientation goal', got=False)
        return GoalSpec(
            distance=self.choice(section['distance'], _join(key, 'distance'), DISTANCES),
            position=position, orientation=orientation,
            samples_per_second=self.number(section.get('samples_per_second', 10.0),
                                           _join(key, 'samples_per_second'), positive=True),
            relative_to_start=self.boolean(section.get('relative_to_start', False),
                                           _join(key, 'relative_to_start')),
            orientation_symmetry=self.symmetry(section.get('orientation_symmetry'),
                                               _join(key, 'orientation_symmetry')))

    def symmetry(self, value, key):
        if value is None:
            return None
        section = self.mapping(value, key, required=('axis', 'order'))
        order = self.integer(section['order'], _join(key, 'order'), minimum=2)
        return SymmetrySpec(axis=self.unit_vector(section['axis'], _join(key, 'axis')),
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
            time = self.number(item['time'], _join(item_key, 'time'), positive=True)
            if goals and time <= goals[-1].time:
                self.fail(_join(item_key, 'time'),
                          f"a time after the previous goal's {goals[-1].time}", item['time'])
            trajectory = self.boolean(item['trajectory'], _join(item_key, 'trajectory'))
            if kind == 'position':
                goals.append(PositionGoal(
                    time, self.vector(item[kind], _join(item_key, kind), 3), trajectory,
                    self.axes(item.get('axes', list(AXES)), _join(item_key, 'axes'))))
            else:
                goals.append(OrientationGoal(time, self.quaternion(item[kind],
                                                                   _join(item_key, kind)),
                                             trajectory))
        return tuple(goals)

    def randomization(self, value, key):
        section = self.mapping(value, key, required=(
            'position', 'orientation', 'friction', 'scale', 'mass'))
        position_key = _join(key, 'position')
        position = self.mapping(section['position'], position_key, required=('x', 'y', 'z'))
        orientation_key = _join(key, 'orientation')
        orientation = self.mapping(section['orientation'], orientation_key,
                                   required=('axis', 'range'))
        scale = self.bounds(section['scale'], _join(key, 'scale'))
        mass = self.bounds(section['mass'], _join(key, 'mass'))
        for name, factor in (('scale', scale), ('mass', mass)):
            if not factor.lower > 0:
                self.fail(_join(key, name), 'positive factors', section[name])
        return RandomizationSpec(
            position=tuple(self.bounds(position[axis], _join(position_key, axis))
                           for axis in 'xyz'),
            orientation_axis=self.unit_vector(orientation['axis'],
                                              _join(orientation_key, 'axis')),
            orientation=self.bounds(orientation['range'], _join(orientation_key, 'range'),
                                    angle=True),
            friction=self.bounds(section['friction'], _join(key, 'friction')),
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
                                        _join(key, 'per_finger_total'))
        if 'delta' in value:
            return ParameterSpec('delta', (self.bounds(value['delta'], _join(key, 'delta'),
                                                       angle=angle),))
        if 'bounds' in value:
            entry_key = _join(key, 'bounds')
            entries = value['bounds']
            if isinstance(entries, list) and entries and isinstance(entries[0], list):
                values = tuple(self.bounds(item, f'{entry_key}[{index}]', angle=angle,
                                           minimum=minimum)
                               for index, item in enumerate(entries))
            else:
                values = (self.bounds(entries, entry_key, angle=angle, minimum=minimum),)
            return ParameterSpec('bounds', values, per_finger_total)
        if per_finger_total:
            self.fail(_join(key, 'per_finger_total'), 'only with bounds', got=False)
        return ParameterSpec('fixed', self.fixed_values(value['fixed'], _join(key, 'fixed'),
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
            return self.parameter(section[name], _join(key, name), **options)

        return MorphologySpec(
            initial_angle=setting('initial_angle', per_joint=True, angle=True),
            finger_position_x=setting('finger_position_x'),
            finger_position_z=setting('finger_position_z'),
            segment_length=setting('segment_length', per_joint=True, allow_total=True),
            axis_angle=setting('axis_angle', per_joint=True, angle=True),
            joint_limits=self.joint_limits(section['joint_limits'],
                                           _join(key, 'joint_limits')),
            friction=setting('friction', minimum=0))

    def joint_limits(self, value, key):
        if isinstance(value, dict) and set(value) == {'fixed'}:
            # a fixed setting is a [lower, upper] pair, or one pair per finger
            raw, fixed_key = value['fixed'], _join(key, 'fixed')
            if isinstance(raw, list) and raw and isinstance(raw[0], list):
                return ParameterSpec('fixed', tuple(
                    self.bounds(pair, f'{fixed_key}[{index}]', angle=True)
                    for index, pair in enumerate(raw)))
            return ParameterSpec('fixed', (self.bounds(raw, fixed_key, angle=True),))
        return self.parameter(value, key, angle=True, allow_none=True)

    def policy(self, value, key):
        kind = self.choice(value.get('kind') if isinstance(value, dict) else value,
                           _join(key, 'kind'), POLICY_KINDS)
        common = ('kind', 'duration')
        if kind == 'torque':
            section = self.mapping(value, key, required=common + ('mode', 'knots', 'torque'),
                                   optional=('gravity_compensation',))
            return PolicySpec(
                kind=kind,
                duration=self.number(section['duration'], _join(key, 'duration'),
                                     positive=True),
                gravity_compensation=self.boolean(section.get('gravity_compensation', False),
                                                  _join(key, 'gravity_compensation')),
                mode=self.choice(section['mode'], _join(key, 'mode'), TORQUE_MODES),
                knots=self.integer(section['knots'], _join(key, 'knots')),
                torque=self.parameter(section['torque'], _join(key, 'torque')))
        section = self.mapping(value, key, required=common + ('keyframe_times', 'target', 'kp',
                                                              'kd'),
                               optional=('gravity_compensation',))
        times_key = _join(key, 'keyframe_times')
        times = section['keyframe_times']
        if not isinstance(times, list) or not times:
            self.fail(times_key, 'a non-empty list of times', times)
        times = tuple(self.number(t, f'{times_key}[{i}]', positive=True)
                      for i, t in enumerate(times))
        if any(b <= a for a, b in zip(times, times[1:])):
            self.fail(times_key, 'strictly increasing times', section['keyframe_times'])
        return PolicySpec(
            kind=kind,
            duration=self.number(section['duration'], _join(key, 'duration'), positive=True),
            gravity_compensation=self.boolean(section.get('gravity_compensation', True),
                                              _join(key, 'gravity_compensation')),
            keyframe_times=times,
            target=self.parameter(section['target'], _join(key, 'target'), angle=True),
            kp=self.parameter(section['kp'], _join(key, 'kp'), minimum=0),
            kd=self.parameter(section['kd'], _join(key, 'kd'), minimum=0))

    def torque_penalty(self, value, key):
        if value is None:
            return None
        section = self.mapping(value, key, required=('threshold', 'weight'))
        weight = self.number(section['weight'], _join(key, 'weight'), positive=True)
        if weight >= 1:
            self.fail(_join(key, 'weight'), 'a weight w in (0, 1)', section['weight'])
        return TorquePenaltySpec(
            threshold=self.number(section['threshold'], _join(key, 'threshold'), minimum=0),
            weight=weight)

    def early_termination(self, value, key):
        if value is None:
            return None
        section = self.mapping(value, key, required=('distance', 'angle'),
                               optional=('checks_per_second', 'horizon'))
        rate = self.number(section.get('checks_per_second', 10.0),
                           _join(key, 'checks_per_second'), positive=True)
        return EarlyTerminationSpec(
            distance=self.number(section['distance'], _join(key, 'distance'), positive=True),
            angle=self.number(section['angle'], _join(key, 'angle'), positive=True,
                              angle=True),
            checks_per_second=rate,
            horizon=self.horizon(section.get('horizon'), _join(key, 'horizon'), 1.0 / rate))

    def horizon(self, value, key, interval):
        if value is None:
            return None
        section = self.mapping(value, key, optional=('start', 'step', 'share'))
        share = self.number(section.get('share', 0.5), _join(key, 'share'), positive=True)
        if share > 1:
            self.fail(_join(key, 'share'), 'a share in (0, 1]', section['share'])
        return HorizonSpec(
            start=self.number(section.get('start', interval), _join(key, 'start'),
                              positive=True),
            step=self.number(section.get('step', interval), _join(key, 'step'),
                             positive=True),
            share=share)

    def physics(self, value, key):
        section = self.mapping(value, key, optional=('engine', 'solver_iterations',
                                                     'contact_breaking_threshold'))
        default = PhysicsSpec()
        return PhysicsSpec(
            engine=self.choice(section.get('engine', default.engine), _join(key, 'engine'),
                               ENGINES),
            solver_iterations=self.integer(section.get('solver_iterations',
                                                       default.solver_iterations),
                                           _join(key, 'solver_iterations')),
            contact_breaking_threshold=self.number(
                section.get('contact_breaking_threshold', default.contact_breaking_threshold),
                _join(key, 'contact_breaking_threshold'), positive=True))

    def worlds(self, value, key):
        section = self.mapping(value, key, optional=('aggregate', 'fraction', 'resample',
                                                     'final_check'))
        default = WorldsSpec()
        aggregate = self.choice(section.get('aggregate', default.aggregate),
                                _join(key, 'aggregate'), WORLD_AGGREGATES)
        fraction_key = _join(key, 'fraction')
        if aggregate == 'worst' and 'fraction' not in section:
            self.fail(fraction_key, 'this key with aggregate: worst (the share of the worst '
                      'worlds each objective averages, in (0, 1])', got=False)
        if aggregate == 'mean' and 'fraction' in section:
            self.fail(fraction_key, 'no fraction with aggregate: mean (it averages every '
                      'world); set aggregate: worst to average the worst worlds', got=False)
        fraction = default.fraction
        if 'fraction' in section:
            fraction = self.number(section['fraction'], fraction_key)
            if not 0 < fraction <= 1:
                self.fail(fraction_key, 'a fraction in (0, 1]', section['fraction'])
        resample = self.choice(section.get('resample', default.resample),
                               _join(key, 'resample'), WORLD_RESAMPLING)
        if resample == 'none' and 'final_check' in section:
            self.fail(_join(key, 'final_check'), 'no final_check without resample: generation '
                      '(it chooses among resampled generations)', got=False)
        return WorldsSpec(aggregate=aggregate, fraction=fraction, resample=resample,
                          final_check=self.integer(section.get('final_check',
                                                               default.final_check),
                                                   _join(key, 'final_check')))

    def archive(self, value, key):
        section = self.mapping(value, key, optional=('descriptors', 'cells', 'ranges',
                                                     'emitters', 'learning_rate'))
        default = ArchiveSpec()
        pairs = {}
        for name in ('descriptors', 'cells', 'ranges'):
            if name in section and (not isinstance(section[name], list)
                                    or len(section[name]) != 2):
                self.fail(_join(key, name), 'a list of two entries, one per descriptor',
                          section[name])
        descriptors = None
        if 'descriptors' in section:
            descriptors = tuple(self.choice(item, f'{key}.descriptors[{index}]',
                                            ARCHIVE_DESCRIPTOR_NAMES)
                                for index, item in enumerate(section['descriptors']))
        if descriptors is not None and descriptors[0] == descriptors[1]:
            self.fail(_join(key, 'descriptors'), 'two different descriptors',
                      list(descriptors))
        cells = tuple(self.integer(item, f'{key}.cells[{index}]') for index, item in
                      enumerate(section.get('cells', default.cells)))
        if 'ranges' in section:
            for index, pair in enumerate(section['ranges']):
                bounds = self.bounds(pair, f'{key}.ranges[{index}]')
                if not bounds.upper > bounds.lower:
                    self.fail(f'{key}.ranges[{index}]', 'lower < upper', pair)
                pairs[index] = (bounds.lower, bounds.upper)
        learning_rate = None
        if 'learning_rate' in section:
            learning_rate = self.number(section['learning_rate'], _join(key, 'learning_rate'))
            if not 0 <= learning_rate <= 1:
                self.fail(_join(key, 'learning_rate'), 'a number in [0, 1]',
                          section['learning_rate'])
        return ArchiveSpec(
            descriptors=descriptors, cells=cells,
            ranges=tuple(pairs[index] for index in range(2)) if pairs else None,
            emitters=(self.integer(section['emitters'], _join(key, 'emitters'))
                      if 'emitters' in section else None),
            learning_rate=learning_rate)

    def weights(self, value, key):
        section = self.mapping(value, key, optional=('position', 'orientation'))
        return WeightsSpec(
            position=self.number(section.get('position', 1.0), _join(key, 'position'),
                                 minimum=0),
            orientation=self.number(section.get('orientation', 0.1),
                                    _join(key, 'orientation'), minimum=0))

    def hierarchy(self, value, key):
        section = self.mapping(value, key, required=(
            'start', 'position_threshold', 'orientation_threshold', 'evaluation_world_states'),
            optional=('stop_structure', 'max_fingers', 'max_joints'))
        stop = section.get('stop_structure')
        return HierarchySpec(
            start=self.structure(section['start'], _join(key, 'start')),
            stop_structure=(None if stop is None
                            else self.structure(stop, _join(key, 'stop_structure'))),
            max_fingers=(None if section.get('max_fingers') is None
                         else self.integer(section['max_fingers'], _join(key, 'max_fingers'))),
            max_joints=(None if section.get('max_joints') is None
                        else self.integer(section['max_joints'], _join(key, 'max_joints'))),
            position_threshold=self.number(section['position_threshold'],
                                           _join(key, 'position_threshold'), minimum=0),
            orientation_threshold=self.number(section['orientation_threshold'],
                                              _join(key, 'orientation_threshold'),
                                              minimum=0, angle=True),
            evaluation_world_states=self.integer(section['evaluation_world_states'],
                                                 _join(key, 'evaluation_world_states')))

    def seed_design(self, value, key):
        if isinstance(value, str):
            base = os.path.dirname(self.source) if os.path.exists(self.source) else '.'
            path = os.path.join(base, value)
            try:
                with open(path, encoding='utf-8') as stream:
                    document = yaml.safe_load(stream)
            except OSError as error:
                self.fail(key, f'a readable seed design file ({error.strerror}: {path})',
                          value)
            except yaml.YAMLError as error:
                self.fail(key, f'a seed design file in valid YAML ({error})', value)
            return _Reader(path).design(document, '')
        return self.design(value, key)

    def design(self, value, key):
        section = self.mapping(value, key, required=('friction', 'fingers', 'controller'))
        fingers_key = _join(key, 'fingers')
        if not isinstance(section['fingers'], list) or not section['fingers']:
            self.fail(fingers_key, 'a non-empty list of fingers', section['fingers'])
        fingers = tuple(self.finger(item, f'{fingers_key}[{index}]')
                        for index, item in enumerate(section['fingers']))
        hand = HandDesign(fingers=fingers, friction=self.number(
            section['friction'], _join(key, 'friction'), minimum=0))
        controller = self.controller(section['controller'], _join(key, 'controller'),
                                     hand.num_joints)
        return Design(hand=hand, controller=controller)

    def finger(self, value, key):
        section = self.mapping(value, key, required=('position', 'segment_lengths', 'joints'))
        joints_key = _join(key, 'joints')
        if not isinstance(section['joints'], list) or not section['joints']:
            self.fail(joints_key, 'a non-empty list of joints', section['joints'])
        joints = tuple(self.joint(item, f'{joints_key}[{index}]')
                       for index, item in enumerate(section['joints']))
        lengths = self.vector(section['segment_lengths'], _join(key, 'segment_lengths'),
                              len(joints), positive=True)
        return FingerDesign(position=self.vector(section['position'], _join(key, 'position'),
                                                 2),
                            segment_lengths=lengths, joints=joints)

    def joint(self, value, key):
        section = self.mapping(value, key, required=('axis_angle', 'initial_angle'),
                               optional=('lower_limit', 'upper_limit'))
        if ('lower_limit' in section) != ('upper_limit' in section):
            self.fail(key, 'both lower_limit and upper_limit, or neither', got=False)
        limits = (None, None)
        if 'lower_limit' in section:
            pair = self.bounds([section['lower_limit'], section['upper_limit']],
                               _join(key, 'lower_limit/upper_limit'), angle=True)
            limits = (pair.lower, pair.upper)
        return JointDesign(
            axis_angle=self.number(section['axis_angle'], _join(key, 'axis_angle'),
                                   angle=True),
            initial_angle=self.number(section['initial_angle'], _join(key, 'initial_angle'),
                                      angle=True),
            lower_limit=limits[0], upper_limit=limits[1])

    def controller(self, value, key, num_joints):
        section = self.mapping(value, key, required=('kind', 'values'), optional=('kp', 'kd'))
        kind = self.choice(section['kind'], _join(key, 'kind'), POLICY_KINDS)
        values_key = _join(key, 'values')
        rows = section['values']
        if not isinstance(rows, list) or not rows:
            self.fail(values_key, f'a list of rows of {num_joints} values', rows)
        values = np.array([self.vector(row, f'{values_key}[{index}]', num_joints, angle=True)
                           for index, row in enumerate(rows)])
        gains = {}
        for name in ('kp', 'kd'):
            if kind == 'pd':
                if name not in section:
                    self.fail(_join(key, name), f'this key for a pd controller ({num_joints} '
                              'values)', got=False)
                # >= 0 as the policy's gain bounds: a design with kd fixed at 0 reads back
                gains[name] = np.array(self.vector(section[name], _join(key, name),
                                                   num_joints, minimum=0))
            elif name in section:
                self.fail(_join(key, name), 'no gains for a torque controller', got=False)
        return ControllerDesign(kind=kind, values=values, kp=gains.get('kp'),
                                kd=gains.get('kd'))


def _yaml_problem(error):
    """Return a YAML error as one line: what is wrong and where (PyYAML spreads it out)."""
    mark = getattr(error, 'problem_mark', None)
    problem = getattr(error, 'problem', None)
    if problem is None or mark is None:
        return ' '.join(str(error).split())
    return f'{problem} at line {mark.line + 1}, column {mark.column + 1}'


def _join(prefix, name):
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
