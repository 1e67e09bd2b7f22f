"""
Descriptors of a design: the axes of a quality-diversity archive (core.search.quality_diversity).

A descriptor is a number computed from a candidate's decoded Design alone, so that the
optimizer computes it without any message change and replay recomputes it exactly. Each one
also knows its range on a task: the least and greatest value any genome of the task's bounds
decodes to, which is the archive's default extent along that axis.

    finger_length     m    the total length of all finger segments: small against long hands
    length_asymmetry  m    the longest finger's length minus the shortest's
    joint_range       rad  the mean span between a joint's lower and upper limit: joints that
                           end on a limit early against free ones
    initial_angle     rad  the mean initial joint angle: fingers curled one way or the other
    finger_spread     m    the greatest distance between two fingers' x on the palm
    friction               the hand's friction coefficient

An archive may also span descriptors of the outcome of a design's rollouts (core.outcomes:
limit_rest, touch), shares of the worlds in [0, 1] that its Evaluation carries.
`DesignDescriptors` gives both: the descriptor vector of a candidate is the named descriptors in
the task's order, those of the design computed from the genome, the others taken from the
candidate's evaluation.

A descriptor whose value a task fixes (its genes have equal bounds) cannot spread an archive:
`descriptor_ranges` names it in a TaskError. Without `optimizer.archive.descriptors` an archive
spans finger_length and joint_range, or finger_length and initial_angle for a task whose
joints have no limits (Tasks 1 to 4).
"""

import dataclasses
from typing import Callable

from hand_codesign.core.outcomes import OUTCOME_NAMES, OUTCOME_RANGE
from hand_codesign.core.task.genome import genome_spec
from hand_codesign.core.task.parts import ARCHIVE_DESCRIPTOR_NAMES, DESCRIPTOR_NAMES, TaskError
import numpy as np


@dataclasses.dataclass(frozen=True)
class Descriptor:
    """A named function of a Design and of the range it takes on a task's genome bounds."""

    name: str
    unit: str
    value: Callable  # Design -> float
    bounds: Callable  # _ValueBounds -> (lower, upper)


class _ValueBounds:
    """The least and greatest physical value of each Design value on a task's genome."""

    def __init__(self, task):
        self.spec = genome_spec(task)
        self.centre = self.spec.decode(self.spec.initial_mean())
        self.structure = tuple(task.structure)

    def of(self, name, fixed):
        """Return (lower, upper) of the gene `name`, or (fixed, fixed) when it is no gene."""
        if name in self.spec.names:
            index = self.spec.index(name)
            return float(self.spec.lower[index]), float(self.spec.upper[index])
        return fixed, fixed

    def finger_lengths(self):
        """Return [(lower, upper)] of each finger's total segment length."""
        bounds = []
        for finger, design in enumerate(self.centre.hand.fingers):
            pairs = [self.of(f'finger{finger}.segment{joint}.length', length)
                     for joint, length in enumerate(design.segment_lengths)]
            bounds.append((sum(p[0] for p in pairs), sum(p[1] for p in pairs)))
        return bounds

    def joints(self):
        """Yield (name prefix, JointDesign at the centre) of every joint, finger by finger."""
        for finger, design in enumerate(self.centre.hand.fingers):
            for joint, joint_design in enumerate(design.joints):
                yield f'finger{finger}.joint{joint}', joint_design


def _spread(pairs):
    """Return the range of max - min over values each within its (lower, upper) pair."""
    lowers, uppers = zip(*pairs)
    return max(0.0, max(lowers) - min(uppers)), max(uppers) - min(lowers)


def _finger_lengths(design):
    return [sum(finger.segment_lengths) for finger in design.hand.fingers]


def _limit_spans(design):
    spans = [joint.upper_limit - joint.lower_limit for finger in design.hand.fingers
             for joint in finger.joints if joint.lower_limit is not None]
    if not spans:
        raise ValueError('the design has no joint limits')
    return spans


def _joint_range_bounds(values):
    lowest, highest = [], []
    for prefix, joint in values.joints():
        if joint.lower_limit is None:
            raise TaskError(f'needs joint limits ({prefix} has none: see '
                            'morphology.joint_limits)')
        # the two limit genes are sorted when decoded: the span is |upper gene - lower gene|
        a_low, a_high = values.of(f'{prefix}.lower_limit', joint.lower_limit)
        b_low, b_high = values.of(f'{prefix}.upper_limit', joint.upper_limit)
        highest.append(max(b_high - a_low, a_high - b_low))
        lowest.append(max(0.0, b_low - a_high, a_low - b_high))
    return float(np.mean(lowest)), float(np.mean(highest))


def _initial_angle_bounds(values):
    pairs = [values.of(f'{prefix}.initial_angle', joint.initial_angle)
             for prefix, joint in values.joints()]
    return float(np.mean([p[0] for p in pairs])), float(np.mean([p[1] for p in pairs]))


def _finger_spread_bounds(values):
    return _spread([values.of(f'finger{finger}.position_x', design.position[0])
                    for finger, design in enumerate(values.centre.hand.fingers)])


DESCRIPTORS = {descriptor.name: descriptor for descriptor in (
    Descriptor('finger_length', 'm', lambda design: float(sum(_finger_lengths(design))),
               lambda values: tuple(map(sum, zip(*values.finger_lengths())))),
    Descriptor('length_asymmetry', 'm',
               lambda design: float(np.ptp(_finger_lengths(design))),
               lambda values: _spread(values.finger_lengths())),
    Descriptor('joint_range', 'rad', lambda design: float(np.mean(_limit_spans(design))),
               _joint_range_bounds),
    Descriptor('initial_angle', 'rad',
               lambda design: float(np.mean([joint.initial_angle
                                             for finger in design.hand.fingers
                                             for joint in finger.joints])),
               _initial_angle_bounds),
    Descriptor('finger_spread', 'm',
               lambda design: float(np.ptp([f.position[0] for f in design.hand.fingers])),
               _finger_spread_bounds),
    Descriptor('friction', '', lambda design: float(design.hand.friction),
               lambda values: values.of('hand.friction', values.centre.hand.friction)),
)}
# DESCRIPTOR_NAMES (task_spec) lists these keys; the task reader checks names against them
# and core.outcomes' OUTCOME_NAMES (ARCHIVE_DESCRIPTOR_NAMES)


def default_descriptors(task):
    """Return finger_length and joint_range, or initial_angle when the joints have no limits."""
    if task.morphology.joint_limits.mode == 'none':
        return ('finger_length', 'initial_angle')
    return ('finger_length', 'joint_range')


def descriptor_ranges(task, names, key='optimizer.archive.descriptors'):
    """
    Return [(lower, upper)] of each named descriptor on the task's genome bounds.

    Raise TaskError naming the task file and `key` when a descriptor is unknown, needs what
    the task has not (joint limits), or does not vary on the task.
    """
    values = _ValueBounds(task)
    ranges = []
    for name in names:
        if name in OUTCOME_NAMES:
            ranges.append(OUTCOME_RANGE)
            continue
        if name not in DESCRIPTORS:
            raise TaskError(f'{task.source}: {key}: expected one of '
                            f'{", ".join(ARCHIVE_DESCRIPTOR_NAMES)}, got {name!r}')
        try:
            lower, upper = DESCRIPTORS[name].bounds(values)
        except TaskError as error:
            raise TaskError(f'{task.source}: {key}: expected descriptors the task has, got '
                            f'{name!r}, which {error}') from None
        if not upper > lower:
            raise TaskError(
                f'{task.source}: {key}: expected descriptors that vary on structure '
                f'{list(task.structure)}, got {name!r}, which the task fixes at '
                f'{lower:.6g}')
        ranges.append((float(lower), float(upper)))
    return ranges


class DesignDescriptors:
    """The named descriptors of a task's candidates: call it with a genome (and outcomes)."""

    def __init__(self, task, names=None):
        self.names = tuple(names or default_descriptors(task))
        self.spec = genome_spec(task)
        self.ranges = descriptor_ranges(task, self.names)
        self.units = tuple(DESCRIPTORS[name].unit if name in DESCRIPTORS else ''
                           for name in self.names)
        self.outcome_names = tuple(name for name in self.names if name in OUTCOME_NAMES)

    def __call__(self, x, outcomes=None):
        """
        Return the descriptor values of normalized genome x.

        `outcomes` ({name: value}, core.outcomes.outcomes_of an evaluation) gives those of the
        outcome; KeyError names one that it lacks.
        """
        design = self.spec.decode(x)
        outcomes = outcomes or {}
        return np.array([outcomes[name] if name in OUTCOME_NAMES
                         else DESCRIPTORS[name].value(design) for name in self.names],
                        dtype=float)


__all__ = ['DESCRIPTOR_NAMES', 'DESCRIPTORS', 'Descriptor', 'DesignDescriptors',
           'default_descriptors', 'descriptor_ranges']
