"""
Reading the search's settings of a task file where the schema's kinds do not reach.

Early termination's horizon (its defaults are the check interval) and the quality-diversity
archive's lists of two; every other key of the search's sections (physics, worlds, weights,
the hierarchy, ...) is read by the schema alone (core.task.schema, core.task.values).
"""

from hand_codesign.core.task.parts import EarlyTerminationSpec, HorizonSpec
from hand_codesign.core.task.values import join_key, ValueReader


class SettingsReader(ValueReader):
    """Reads the values of the search's sections that need more than their kind."""

    def early_termination(self, spec, value, key):
        """Return EarlyTerminationSpec; its horizon's start and step default to one check."""
        values = self.section(EarlyTerminationSpec, value, key, skip=('horizon',))
        interval = 1.0 / values['checks_per_second']
        horizon = value.get('horizon')
        values['horizon'] = None if horizon is None else HorizonSpec(**self.section(
            HorizonSpec, horizon, join_key(key, 'horizon'),
            given={'start': interval, 'step': interval}))
        return EarlyTerminationSpec(**values)

    def pair(self, value, key):
        """Fail unless an archive's value is a list of two entries, one per descriptor."""
        if not isinstance(value, list) or len(value) != 2:
            self.fail(key, 'a list of two entries, one per descriptor', value)
        return value

    def archive_descriptors(self, spec, value, key):
        descriptors = tuple(self.choice(item, f'{key}[{index}]', spec.choices)
                            for index, item in enumerate(self.pair(value, key)))
        if descriptors[0] == descriptors[1]:
            self.fail(key, 'two different descriptors', list(descriptors))
        return descriptors

    def archive_cells(self, spec, value, key):
        return tuple(self.integer(item, f'{key}[{index}]')
                     for index, item in enumerate(self.pair(value, key)))

    def archive_ranges(self, spec, value, key):
        pairs = []
        for index, pair in enumerate(self.pair(value, key)):
            bounds = self.bounds(pair, f'{key}[{index}]')
            if not bounds.upper > bounds.lower:
                self.fail(f'{key}[{index}]', 'lower < upper', pair)
            pairs.append((bounds.lower, bounds.upper))
        return tuple(pairs)
