"""Reading a design of a task file: a seed design, its fingers, joints and controller."""

import os

from hand_codesign.core.design import (ControllerDesign, Design, FingerDesign, HandDesign,
                                       JointDesign)
from hand_codesign.core.task.parts import POLICY_KINDS
from hand_codesign.core.task.values import join_key, ValueReader
import numpy as np
import yaml


class DesignReader(ValueReader):
    """Reads a Design (core.design) from YAML: a task's seed design, or a design file."""

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
            return type(self)(path).design(document, '')
        return self.design(value, key)

    def design(self, value, key):
        section = self.mapping(value, key, required=('friction', 'fingers', 'controller'),
                               optional=('base_position', 'base_yaw'))
        fingers = self.items(section['fingers'], join_key(key, 'fingers'), 'fingers',
                             self.finger)
        placed = {}   # a searched palm placement (core.task.genome), both or neither
        if ('base_position' in section) != ('base_yaw' in section):
            self.fail(key, 'both base_position and base_yaw, or neither', got=False)
        if 'base_position' in section:
            placed = {'base_position': self.vector(section['base_position'],
                                                   join_key(key, 'base_position'), 3),
                      'base_yaw': self.number(section['base_yaw'], join_key(key, 'base_yaw'),
                                              angle=True)}
        hand = HandDesign(fingers=fingers, friction=self.number(
            section['friction'], join_key(key, 'friction'), minimum=0), **placed)
        controller = self.controller(section['controller'], join_key(key, 'controller'),
                                     hand.num_joints)
        return Design(hand=hand, controller=controller)

    def finger(self, value, key):
        section = self.mapping(value, key, required=('position', 'segment_lengths', 'joints'))
        joints = self.items(section['joints'], join_key(key, 'joints'), 'joints', self.joint)
        lengths = self.vector(section['segment_lengths'], join_key(key, 'segment_lengths'),
                              len(joints), positive=True)
        return FingerDesign(position=self.vector(section['position'], join_key(key, 'position'),
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
                               join_key(key, 'lower_limit/upper_limit'), angle=True)
            limits = (pair.lower, pair.upper)
        return JointDesign(
            axis_angle=self.number(section['axis_angle'], join_key(key, 'axis_angle'),
                                   angle=True),
            initial_angle=self.number(section['initial_angle'], join_key(key, 'initial_angle'),
                                      angle=True),
            lower_limit=limits[0], upper_limit=limits[1])

    def controller(self, value, key, num_joints):
        section = self.mapping(value, key, required=('kind', 'values'), optional=('kp', 'kd'))
        kind = self.choice(section['kind'], join_key(key, 'kind'), POLICY_KINDS)
        values_key = join_key(key, 'values')
        rows = section['values']
        if not isinstance(rows, list) or not rows:
            self.fail(values_key, f'a list of rows of {num_joints} values', rows)
        values = np.array([self.vector(row, f'{values_key}[{index}]', num_joints, angle=True)
                           for index, row in enumerate(rows)])
        gains = {}
        for name in ('kp', 'kd'):
            if kind == 'pd':
                if name not in section:
                    self.fail(join_key(key, name), f'this key for a pd controller ({num_joints} '
                              'values)', got=False)
                # >= 0 as the policy's gain bounds: a design with kd fixed at 0 reads back
                gains[name] = np.array(self.vector(section[name], join_key(key, name),
                                                   num_joints, minimum=0))
            elif name in section:
                self.fail(join_key(key, name), 'no gains for a torque controller', got=False)
        return ControllerDesign(kind=kind, values=values, kp=gains.get('kp'),
                                kd=gains.get('kd'))
