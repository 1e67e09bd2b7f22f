"""
The task specification: a YAML file, validated into a frozen tree of dataclasses.

A task says what the hand must do with one object (section III.A of the paper), which hand
parameters and controller values the optimizer searches and within which bounds (III.B), how
the result is scored (III.C) and with which budget. All values are SI units: metres, radians,
kilograms, newton metres, seconds.

Every key of a task file is declared once, as a field of the Task (core.task.spec) or of its
parts (core.task.parts) with core.task.schema.key: its meaning, unit, default, bounds or
choices. docs/TASK.md lists them all (its table is written from those declarations), with the
parameter settings, goals, worlds, policies and seed designs explained.

`load_task(path)` and `parse_task(text)` return a Task or raise TaskError naming the file, the
dotted key, what was expected and what came.
"""

# The task room: its parts (parts), the Task (spec), its reader (reader, built on values,
# settings_reader and design_reader), its cross-field rules (checks), the genome a task's
# bounds define (genome), the descriptors of a design on them (descriptors) and the Variant
# of a task a candidate is evaluated on (variant). This face is the import path users know;
# the room's modules import each other by their own paths, never through this face, so loading
# it cannot run in a circle. The room imports only core's root modules (design, rotations,
# outcomes) besides its own; the schema (schema) declares every key, the table of
# docs/TASK.md is written from it (document).
from hand_codesign.core.rotations import axis_angle_quaternion
from hand_codesign.core.task.parts import (ALGORITHMS, ArchiveSpec, AXES, Bounds,
                                           CONTACT_PARAMETERS, ContactSpec, DISTANCES,
                                           EarlyTerminationSpec, GoalSpec, HandSpec, HierarchySpec,
                                           HorizonSpec, MORPHOLOGY_PARAMETERS, MorphologySpec,
                                           ObjectSpec, OrientationGoal, PARAMETER_MODES,
                                           ParameterSpec, PhysicsSpec, POLICY_KINDS, PolicySpec,
                                           PositionGoal, RacingSpec, RandomizationSpec,
                                           resting_height, RESTING_TOLERANCE, SHAPES, STARTS,
                                           SymmetrySpec, TaskError, TORQUE_MODES,
                                           TorquePenaltySpec, WeightsSpec, WORLD_AGGREGATES,
                                           WORLD_RESAMPLING, WorldsSpec)
from hand_codesign.core.task.reader import load_task, parse_design, parse_task
from hand_codesign.core.task.spec import Task

__all__ = [
    'ALGORITHMS', 'ArchiveSpec', 'AXES', 'axis_angle_quaternion', 'Bounds',
    'CONTACT_PARAMETERS', 'ContactSpec', 'DISTANCES',
    'EarlyTerminationSpec', 'GoalSpec', 'HandSpec', 'HierarchySpec', 'HorizonSpec', 'load_task',
    'MORPHOLOGY_PARAMETERS', 'MorphologySpec', 'ObjectSpec', 'OrientationGoal', 'PARAMETER_MODES',
    'ParameterSpec', 'parse_design', 'parse_task', 'PhysicsSpec', 'POLICY_KINDS', 'PolicySpec',
    'PositionGoal', 'RacingSpec', 'RandomizationSpec', 'resting_height', 'RESTING_TOLERANCE',
    'SHAPES', 'STARTS', 'SymmetrySpec', 'Task', 'TaskError', 'TORQUE_MODES', 'TorquePenaltySpec',
    'WeightsSpec', 'WORLD_AGGREGATES', 'WORLD_RESAMPLING', 'WorldsSpec',
]
