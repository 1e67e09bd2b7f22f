"""
Domain-randomized world states (section III.A): variations of the object's initial state.

`world_states(task)` draws a fixed set, uniform in the task's randomization ranges, from a
numpy Generator seeded with task.seed: every candidate of a run meets the same worlds, and the
first k worlds of a larger set are the k worlds of a smaller one (one row of draws per world).
With `worlds: {resample: generation}` each generation's candidates carry a draw number k >= 1
(Candidate.world_draw, task.world_draw) and meet `world_states` from the stream
[seed, RESAMPLE_STREAM, k]: a fresh set per generation, the same for every candidate of it.
Streams of one seed, as numpy SeedSequence entropy: [seed] the fixed (training) worlds,
[seed, HELD_OUT_STREAM] the hierarchy's held-out worlds, [seed, UNSEEN_STREAM (11)] the unseen
worlds of core.experiments.measures, [seed, RESAMPLE_STREAM, k] the k-th draw. SeedSequence pads
entropy with zeros, so [seed, s] is [seed, s, 0]: k starts at 1, and RESAMPLE_STREAM is neither 0,
1 nor 11, so no draw repeats another stream (test_worlds compares the values).
With `physics.contact` each world also draws its contact parameters (`with_contact`), from its
set's entropy with CONTACT_STREAM (31) appended ([seed, 31], [seed, 1, 31], [seed, 11, 31],
[seed, 21, k, 31]): a generator of their own, so the seven quantities above stay as they were.
The nominal world of stage 1 and the grid's worlds draw none: they meet the engines' own contact.
`grid_world_states(task, 5)` puts every randomized quantity (a range of non-zero width) at 5
evenly spaced values, all combinations: the robustness grid of Fig. 3 (Task 4 randomizes six
quantities: 5^6 = 15,625 worlds). `object_state(task, world)` is the object's initial state
in a world, which the simulator builds.
"""

import dataclasses
from dataclasses import dataclass
import itertools
from typing import List, Optional, Tuple

from hand_codesign.core.rotations import axis_angle_quaternion, quaternion_multiply
from hand_codesign.core.task import CONTACT_PARAMETERS, resting_height, Task
import numpy as np

HELD_OUT_STREAM = 1  # second entropy word of the held-out worlds' generator
RESAMPLE_STREAM = 21  # second entropy word of the resampled draws' generators (third: k)
# appended to a set's entropy for its worlds' contact parameters (physics.contact): their own
# generator, so the seven quantities of every existing world stay what they were
CONTACT_STREAM = 31

QUANTITIES = ('position_x', 'position_y', 'position_z', 'orientation', 'friction', 'scale',
              'mass')


@dataclass(frozen=True)
class ContactState:
    """One world's contact parameters of the object; None: the engine's own."""

    stiffness: Optional[float] = None  # N/m
    damping: Optional[float] = None  # N s/m
    restitution: Optional[float] = None


@dataclass(frozen=True)
class WorldState:
    """One world: deltas and factors applied to the task's nominal object."""

    position_delta: Tuple[float, float, float]  # m, world axes
    orientation_delta: float  # rad about task.randomization.orientation_axis
    friction_delta: float  # added to the object's friction
    scale: float  # factor on every dimension of the object
    mass_factor: float  # factor on the object's mass
    # drawn only for a task with physics.contact; None: the engines' own contact
    contact: Optional[ContactState] = None

    @classmethod
    def nominal(cls):
        """Return the world without any randomization."""
        return cls((0.0, 0.0, 0.0), 0.0, 0.0, 1.0, 1.0)

    @classmethod
    def from_values(cls, values):
        """Return the world of seven values in QUANTITIES order."""
        x, y, z, orientation, friction, scale, mass = (float(v) for v in values)
        return cls((x, y, z), orientation, friction, scale, mass)


@dataclass(frozen=True)
class ObjectState:
    """The object's initial state in one world, ready to build (world frame, SI units)."""

    position: Tuple[float, float, float]
    orientation: Tuple[float, float, float, float]  # x, y, z, w
    scale: float  # factor on the nominal dimensions
    mass: float  # kg
    friction: float
    size: Tuple[float, ...]  # box: (x, y, z) edges; sphere: (radius,); capsule: (radius, length)
    contact: Optional[ContactState] = None  # the world's contact parameters (None: engine's)


def _ranges(task: Task):
    return [bounds for _, bounds in task.randomization.quantities()]


def world_states(task: Task, count=None) -> List[WorldState]:
    """
    Return the task's worlds (num_world_states or `count`), uniform in the ranges, seeded.

    Stage 1 of a two-stage task has the nominal world only. With task.held_out the draws come
    from another stream of the same seed, independent of the training worlds: no held-out
    world repeats a training world (the draws are continuous), so a check on them measures
    how a design does on worlds it was not optimized on. With task.world_draw = k >= 1 they
    are the k-th resampled draw (see the module doc).
    """
    if task.stage == 1:
        return [WorldState.nominal()]
    count = task.num_world_states if count is None else int(count)
    generator = np.random.default_rng(world_stream(task))
    uniform = generator.random((count, len(QUANTITIES)))
    lower = np.array([bounds.lower for bounds in _ranges(task)])
    width = np.array([bounds.width for bounds in _ranges(task)])
    worlds = [WorldState.from_values(row) for row in lower + uniform * width]
    return with_contact(task, worlds, world_stream(task))


def with_contact(task: Task, worlds, stream) -> List[WorldState]:
    """
    Return the worlds, each with contact parameters drawn in physics.contact's ranges.

    Args:
        task: the Task; without physics.contact the worlds come back as they are.
        worlds: the WorldStates of one set, drawn from the entropy `stream`.
        stream: that set's SeedSequence entropy (an int or a list of ints).

    Returns:
        list of WorldState. The draws come from the set's entropy with CONTACT_STREAM
        appended, one row per world (the first k worlds of a larger set keep theirs), a
        column per parameter of CONTACT_PARAMETERS whether it is given or not, so adding a
        range leaves the others' draws as they were.
    """
    contact = task.physics.contact
    if contact is None:
        return list(worlds)
    entropy = [*np.atleast_1d(stream).tolist(), CONTACT_STREAM]
    uniform = np.random.default_rng(entropy).random((len(worlds), len(CONTACT_PARAMETERS)))
    drawn = []
    for world, row in zip(worlds, uniform):
        values = {}
        for column, name in enumerate(CONTACT_PARAMETERS):
            bounds = getattr(contact, name)
            if bounds is not None:
                values[name] = float(bounds.lower + row[column] * bounds.width)
        drawn.append(dataclasses.replace(world, contact=ContactState(**values)))
    return drawn


def world_stream(task: Task):
    """Return the SeedSequence entropy of the task's worlds: fixed, held out or a draw."""
    if task.held_out:
        return [task.seed, HELD_OUT_STREAM]
    if task.world_draw:
        return [task.seed, RESAMPLE_STREAM, int(task.world_draw)]
    return task.seed


def randomized_quantities(task: Task):
    """Return the names of the quantities whose range has a non-zero width."""
    return [name for name, bounds in task.randomization.quantities() if bounds.width > 0]


def grid_world_states(task: Task, values_per_quantity=5) -> List[WorldState]:
    """Return every combination of `values_per_quantity` evenly spaced values per range."""
    axes = []
    for bounds in _ranges(task):
        if bounds.width > 0:
            axes.append(np.linspace(bounds.lower, bounds.upper, values_per_quantity))
        else:
            axes.append(np.array([bounds.lower]))
    return [WorldState.from_values(values) for values in itertools.product(*axes)]


def object_state(task: Task, world: WorldState) -> ObjectState:
    """
    Return the object's initial state in `world`.

    The orientation delta turns the object about the randomization axis (world frame); an
    object starting on the plane is then put down on it: its z is the resting height of the
    scaled, turned object (its position delta along z is zero by validation).
    """
    spec = task.object_spec
    axis = task.randomization.orientation_axis
    turn = axis_angle_quaternion(axis, world.orientation_delta)
    orientation = np.array(quaternion_multiply(turn, spec.orientation), dtype=float)
    orientation = tuple(float(v) for v in orientation / np.linalg.norm(orientation))
    position = [float(p + d) for p, d in zip(spec.position, world.position_delta)]
    if spec.start == 'plane':
        position[2] = resting_height(spec, world.scale, orientation)
    if spec.shape == 'box':
        size = tuple(s * world.scale for s in spec.size)
    elif spec.shape == 'sphere':
        size = (spec.radius * world.scale,)
    else:
        size = (spec.radius * world.scale, spec.length * world.scale)
    return ObjectState(position=tuple(position), orientation=orientation, scale=world.scale,
                       mass=spec.mass * world.mass_factor,
                       friction=max(0.0, spec.friction + world.friction_delta), size=size,
                       contact=world.contact)
