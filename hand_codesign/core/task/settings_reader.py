"""
Reading the search's settings of a task file.

Early termination and its horizon, physics, worlds, the quality-diversity archive, the
objectives' weights and the hierarchy: the sections that set up the search, not the task.
"""


from hand_codesign.core.task.parts import (ARCHIVE_DESCRIPTOR_NAMES, ArchiveSpec,
                                           EarlyTerminationSpec, ENGINES, HierarchySpec,
                                           HorizonSpec, PhysicsSpec, RacingSpec, WeightsSpec,
                                           WORLD_AGGREGATES, WORLD_RESAMPLING, WorldsSpec)
from hand_codesign.core.task.values import join_key, ValueReader


class SettingsReader(ValueReader):
    """Reads the sections of a task file that set up the search rather than the task."""

    def early_termination(self, value, key):
        if value is None:
            return None
        section = self.mapping(value, key, required=('distance', 'angle'),
                               optional=('checks_per_second', 'horizon'))
        rate = self.number(section.get('checks_per_second', 10.0),
                           join_key(key, 'checks_per_second'), positive=True)
        return EarlyTerminationSpec(
            distance=self.number(section['distance'], join_key(key, 'distance'), positive=True),
            angle=self.number(section['angle'], join_key(key, 'angle'), positive=True,
                              angle=True),
            checks_per_second=rate,
            horizon=self.horizon(section.get('horizon'), join_key(key, 'horizon'), 1.0 / rate))

    def horizon(self, value, key, interval):
        if value is None:
            return None
        section = self.mapping(value, key, optional=('start', 'step', 'share'))
        share = self.number(section.get('share', 0.5), join_key(key, 'share'), positive=True)
        if share > 1:
            self.fail(join_key(key, 'share'), 'a share in (0, 1]', section['share'])
        return HorizonSpec(
            start=self.number(section.get('start', interval), join_key(key, 'start'),
                              positive=True),
            step=self.number(section.get('step', interval), join_key(key, 'step'),
                             positive=True),
            share=share)

    def physics(self, value, key):
        section = self.mapping(value, key, optional=('engine', 'solver_iterations',
                                                     'contact_breaking_threshold'))
        default = PhysicsSpec()
        return PhysicsSpec(
            engine=self.choice(section.get('engine', default.engine), join_key(key, 'engine'),
                               ENGINES),
            solver_iterations=self.integer(section.get('solver_iterations',
                                                       default.solver_iterations),
                                           join_key(key, 'solver_iterations')),
            contact_breaking_threshold=self.number(
                section.get('contact_breaking_threshold', default.contact_breaking_threshold),
                join_key(key, 'contact_breaking_threshold'), positive=True))

    def worlds(self, value, key):
        section = self.mapping(value, key, optional=('aggregate', 'fraction', 'resample',
                                                     'final_check', 'racing'))
        default = WorldsSpec()
        aggregate = self.choice(section.get('aggregate', default.aggregate),
                                join_key(key, 'aggregate'), WORLD_AGGREGATES)
        fraction_key = join_key(key, 'fraction')
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
                               join_key(key, 'resample'), WORLD_RESAMPLING)
        if resample == 'none' and 'final_check' in section:
            self.fail(join_key(key, 'final_check'), 'no final_check without resample: generation '
                      '(it chooses among resampled generations)', got=False)
        racing = (self.racing(section['racing'], join_key(key, 'racing'))
                  if 'racing' in section else None)
        return WorldsSpec(aggregate=aggregate, fraction=fraction, resample=resample,
                          final_check=self.integer(section.get('final_check',
                                                               default.final_check),
                                                   join_key(key, 'final_check')),
                          racing=racing)

    def racing(self, value, key):
        section = self.mapping(value or {}, key, optional=('rounds', 'range', 'delta'))
        default = RacingSpec()
        delta = self.number(section.get('delta', default.delta), join_key(key, 'delta'),
                            positive=True)
        if not delta < 1:
            self.fail(join_key(key, 'delta'), 'a probability in (0, 1)', section['delta'])
        return RacingSpec(rounds=self.integer(section.get('rounds', default.rounds),
                                              join_key(key, 'rounds'), minimum=2),
                          value_range=self.number(section.get('range', default.value_range),
                                                  join_key(key, 'range'), positive=True),
                          delta=delta)

    def archive(self, value, key):
        section = self.mapping(value, key, optional=('descriptors', 'cells', 'ranges',
                                                     'emitters', 'learning_rate'))
        default = ArchiveSpec()
        pairs = {}
        for name in ('descriptors', 'cells', 'ranges'):
            if name in section and (not isinstance(section[name], list)
                                    or len(section[name]) != 2):
                self.fail(join_key(key, name), 'a list of two entries, one per descriptor',
                          section[name])
        descriptors = None
        if 'descriptors' in section:
            descriptors = tuple(self.choice(item, f'{key}.descriptors[{index}]',
                                            ARCHIVE_DESCRIPTOR_NAMES)
                                for index, item in enumerate(section['descriptors']))
        if descriptors is not None and descriptors[0] == descriptors[1]:
            self.fail(join_key(key, 'descriptors'), 'two different descriptors',
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
            learning_rate = self.number(section['learning_rate'], join_key(key, 'learning_rate'))
            if not 0 <= learning_rate <= 1:
                self.fail(join_key(key, 'learning_rate'), 'a number in [0, 1]',
                          section['learning_rate'])
        return ArchiveSpec(
            descriptors=descriptors, cells=cells,
            ranges=tuple(pairs[index] for index in range(2)) if pairs else None,
            emitters=(self.integer(section['emitters'], join_key(key, 'emitters'))
                      if 'emitters' in section else None),
            learning_rate=learning_rate)

    def weights(self, value, key):
        section = self.mapping(value, key, optional=('position', 'orientation'))
        return WeightsSpec(
            position=self.number(section.get('position', 1.0), join_key(key, 'position'),
                                 minimum=0),
            orientation=self.number(section.get('orientation', 0.1),
                                    join_key(key, 'orientation'), minimum=0))

    def hierarchy(self, value, key):
        section = self.mapping(value, key, required=(
            'start', 'position_threshold', 'orientation_threshold', 'evaluation_world_states'),
            optional=('stop_structure', 'max_fingers', 'max_joints'))
        stop = section.get('stop_structure')
        return HierarchySpec(
            start=self.structure(section['start'], join_key(key, 'start')),
            stop_structure=(None if stop is None
                            else self.structure(stop, join_key(key, 'stop_structure'))),
            max_fingers=(None if section.get('max_fingers') is None
                         else self.integer(section['max_fingers'], join_key(key, 'max_fingers'))),
            max_joints=(None if section.get('max_joints') is None
                        else self.integer(section['max_joints'], join_key(key, 'max_joints'))),
            position_threshold=self.number(section['position_threshold'],
                                           join_key(key, 'position_threshold'), minimum=0),
            orientation_threshold=self.number(section['orientation_threshold'],
                                              join_key(key, 'orientation_threshold'),
                                              minimum=0, angle=True),
            evaluation_world_states=self.integer(section['evaluation_world_states'],
                                                 join_key(key, 'evaluation_world_states')))
