"""
Contact parameters drawn per world (`physics.contact`): read, refused, drawn and applied.

The ranges read and their mistakes refused in one line; each world's draw deterministic, in
its ranges and different between worlds, without moving any existing world; a task without
the section evaluating bit for bit as before (objectives recorded before the section
existed); and the parameters acting in both engines: a stiffer contact lets a resting box sink
less, a restitution makes a dropped box bounce. Tiny scenes: a few worlds, short rollouts.
"""

import math
import pathlib

from hand_codesign.commands.check import worlds_text
from hand_codesign.core.evaluate import evaluate, evaluate_design
from hand_codesign.core.experiments.measures import unseen_world_states
from hand_codesign.core.run.preview import preview
from hand_codesign.core.sim.mujoco_sim import bouncing_solref, contact_solref, stiff_solref
from hand_codesign.core.sim.worlds import ContactState, QUANTITIES, world_states, WorldState
from hand_codesign.core.task import parse_task, TaskError
from hand_codesign.core.task.genome import genome_spec
import numpy as np
import pytest
import yaml

TASK = pathlib.Path(__file__).resolve().parents[3] / 'config' / 'tasks' / 'task5.yaml'
ENGINES = ('pybullet', 'mujoco')
SOFT = {'stiffness': [40.0, 60.0], 'damping': [0.5, 1.0]}
# for a 0.1 kg box at most 1000 N/m and 20 N s/m in MuJoCo; damped about critically, as
# MuJoCo's soft contact chatters at 5 ms steps below a damping ratio of about 0.6
RESTING = {'soft': {'stiffness': [40.0, 60.0], 'damping': [6.0, 8.0]},
           'stiff': {'stiffness': [400.0, 600.0], 'damping': [16.0, 20.0]}}
# task5 on 3 worlds, genome linspace(0.2, 0.8), objectives as evaluated before physics.contact
BEFORE = {'pybullet': ('0x1.112682ce550a4p-7', '0x1.cb2e424f779a9p-3'),
          'mujoco': ('0x1.112741116ababp-7', '0x1.cb2e8fde584bcp-3')}


def task_with(physics, worlds=3, **changes):
    """Return task5 with the physics mapping (and other top-level keys), on `worlds` worlds."""
    document = yaml.safe_load(TASK.read_text())
    if 'object' in changes:  # a box of one mass in every world
        document['randomization']['mass'] = [1.0, 1.0]
    document['physics'] = physics
    document['world_states'] = worlds
    document.update(changes)
    return parse_task(yaml.safe_dump(document), source='contact.yaml')


def middle_design(task):
    """Return the design at the middle of the task's genome."""
    spec = genome_spec(task)
    return spec.decode(np.full(spec.size, 0.5))


def away_from_the_hand(start='plane', height=0.02, mass=0.03):
    """Return task5's object moved 0.5 m from the hand, which never touches it."""
    document = yaml.safe_load(TASK.read_text())
    thing = dict(document['object'], start=start, position=[0.5, 0.0, height], mass=mass)
    goals = {'distance': 'euclidean', 'orientation': [],
             'position': [{'time': 1.5, 'position': [0.5, 0.0, 0.02],
                           'trajectory': False}]}
    return {'object': thing, 'goals': goals}


def test_the_ranges_are_read_and_absent_is_none():
    task = task_with({'engines': list(ENGINES), 'contact': SOFT})
    contact = task.physics.contact
    assert (contact.stiffness.lower, contact.stiffness.upper) == (40.0, 60.0)
    assert contact.restitution is None
    assert [name for name, _ in contact.ranges()] == ['stiffness', 'damping']
    assert task_with({}).physics.contact is None


@pytest.mark.parametrize('contact, message', [
    ({'stiffness': [60, 40], 'damping': [1, 2]},
     'physics.contact.stiffness: expected lower <= upper, got [60, 40]'),
    ({'stiffness': [-5, 40], 'damping': [1, 2]},
     'physics.contact.stiffness: expected a pair [lower, upper] of positive numbers, got '
     '[-5, 40]'),
    ({'damping': [-1, 2], 'stiffness': [1, 2]},
     'physics.contact.damping[0]: expected a number >= 0, got -1'),
    ({'restitution': [0.2, 1.5]},
     'physics.contact.restitution: expected coefficients in [0, 1], got [0.2, 1.5]'),
    ({'friction_model': 'cone'}, 'physics.contact.friction_model: expected no such key '
     '(allowed: stiffness, damping, restitution)'),
    ({}, 'physics.contact: expected at least one of stiffness, damping, restitution'),
    ({'stiffness': [40, 60]}, 'physics.contact.damping: expected a range beside stiffness'),
    ({'stiffness': 50, 'damping': [1, 2]},
     'physics.contact.stiffness: expected a pair [lower, upper], got 50'),
])
def test_bad_ranges_are_one_line_naming_the_key(contact, message):
    with pytest.raises(TaskError) as refused:
        task_with({'engine': 'pybullet', 'contact': contact})
    assert str(refused.value).startswith(f'contact.yaml: {message}'), str(refused.value)
    assert '\n' not in str(refused.value)


@pytest.mark.parametrize('contact, message', [
    ({'stiffness': [40, 500], 'damping': [0.5, 1]}, 'physics.contact.stiffness: expected an '
     'upper end of at most 198 N/m with mujoco in physics.engines (the most MuJoCo steps '
     'stably at time_step 0.005 s for the lightest object, 0.0198 kg), got 500'),
    ({'stiffness': [40, 60], 'damping': [0.5, 9]}, 'physics.contact.damping: expected an '
     'upper end of at most 3.96 N s/m'),
    ({'stiffness': [40, 60], 'damping': [0.5, 1], 'restitution': [0.2, 0.5]},
     'physics.contact.restitution: expected no restitution beside damping with mujoco'),
])
def test_what_mujoco_cannot_model_is_refused_for_mujoco_only(contact, message):
    with pytest.raises(TaskError) as refused:
        task_with({'engines': list(ENGINES), 'contact': contact})
    assert str(refused.value).startswith(f'contact.yaml: {message}'), str(refused.value)
    assert task_with({'engine': 'pybullet', 'contact': contact}).physics.contact is not None


def test_each_world_draws_its_own_contact_in_the_ranges_deterministically():
    contact = {'stiffness': [40.0, 60.0], 'damping': [0.5, 1.0], 'restitution': [0.1, 0.6]}
    task = task_with({'engine': 'pybullet', 'contact': contact}, worlds=16)
    worlds = world_states(task)
    assert worlds == world_states(task_with({'engine': 'pybullet', 'contact': contact},
                                            worlds=16))
    for name, (lower, upper) in contact.items():
        values = [getattr(world.contact, name) for world in worlds]
        assert all(lower <= value <= upper for value in values), name
        assert len(set(values)) == len(values), name
    # the first worlds of a larger set are the worlds of a smaller one; another seed, others
    assert world_states(task.replace(num_world_states=4)) == worlds[:4]
    assert world_states(task.replace(seed=task.seed + 1)) != worlds
    # each range has its own column: leaving one out keeps the others' draws
    fewer = task_with({'engine': 'pybullet', 'contact': {'restitution': [0.1, 0.6]}},
                      worlds=16)
    assert [w.contact.restitution for w in world_states(fewer)] == [
        w.contact.restitution for w in worlds]
    # every set of worlds draws its own: held out, unseen, resampled
    sets = [worlds, world_states(task.replace(held_out=True)), unseen_world_states(task, 16),
            world_states(task.replace(world_draw=1)), world_states(task.replace(world_draw=2))]
    stiffnesses = [w.contact.stiffness for each in sets for w in each]
    assert len(set(stiffnesses)) == len(stiffnesses)


def test_the_section_leaves_the_seven_quantities_of_every_world_as_they_were():
    task = task_with({'engine': 'pybullet', 'contact': SOFT}, worlds=8)
    plain = task_with({}, worlds=8)
    assert [w.contact for w in world_states(plain)] == [None] * 8
    assert [w.__class__(*_seven(w)) for w in world_states(task)] == world_states(plain)
    # and they are the draws of numpy's generator seeded with the task's seed, as ever
    uniform = np.random.default_rng(plain.seed).random((8, len(QUANTITIES)))
    ranges = [bounds for _, bounds in plain.randomization.quantities()]
    rows = np.array([b.lower for b in ranges]) + uniform * np.array([b.width for b in ranges])
    assert world_states(plain) == [WorldState.from_values(row) for row in rows]


def _seven(world):
    return (world.position_delta, world.orientation_delta, world.friction_delta, world.scale,
            world.mass_factor)


@pytest.mark.parametrize('engine', ENGINES)
def test_a_task_without_the_section_evaluates_bit_for_bit_as_before(engine):
    task = task_with({'engine': engine})
    evaluation = evaluate(np.linspace(0.2, 0.8, genome_spec(task).size), task)
    assert tuple(value.hex() for value in evaluation.objectives) == BEFORE[engine]


def test_a_task_with_the_section_evaluates_in_both_engines_deterministically():
    task = task_with({'engines': list(ENGINES), 'contact': SOFT}, worlds=2)
    x = np.linspace(0.2, 0.8, genome_spec(task).size)
    first, second = evaluate(x, task), evaluate(x, task)
    assert first.final_poses.shape == (4, 7) and not first.collision
    assert first.unstable_worlds == 0
    assert first.objectives.tobytes() == second.objectives.tobytes()
    assert first.final_poses.tobytes() == second.final_poses.tobytes()
    plain = evaluate(x, task_with({'engines': list(ENGINES)}, worlds=2))
    assert first.final_poses.tobytes() != plain.final_poses.tobytes()


@pytest.mark.parametrize('engine', ENGINES)
def test_a_stiffer_contact_lets_a_resting_box_sink_less(engine):
    heights = {}
    for name, contact in RESTING.items():
        task = task_with({'engine': engine, 'contact': contact}, worlds=2,
                         **away_from_the_hand(mass=0.1))
        evaluation = evaluate_design(middle_design(task), task)
        heights[name] = evaluation.final_poses[:, 2]
    rest = [w.scale * 0.02 for w in world_states(task)]  # the box's resting height
    sunk_soft, sunk_stiff = rest - heights['soft'], rest - heights['stiff']
    # Bullet: m g / (4 K), about 4 mm against 0.5; MuJoCo: about (1 - d) / d of that
    least = 1e-3 if engine == 'pybullet' else 1e-5
    assert (sunk_soft - sunk_stiff > least).all(), (sunk_soft, sunk_stiff)
    assert (sunk_stiff > 0).all()


@pytest.mark.parametrize('engine', ENGINES)
def test_a_restitution_makes_a_dropped_box_bounce(engine):
    def highest_after_impact(contact):
        physics = {'engine': engine}
        if contact:
            physics['contact'] = contact
        task = task_with(physics, worlds=1, **away_from_the_hand('midair', 0.07))
        heights = []
        evaluate_design(middle_design(task), task,
                        on_frame=lambda step, sim: heights.append(sim.object_pose()[0][2]))
        lowest = int(np.argmin(heights))
        return max(heights[lowest:]) - heights[lowest]

    assert highest_after_impact({'restitution': [0.8, 0.9]}) > 5e-3
    assert highest_after_impact(None) < 1e-3


def test_mujoco_maps_stiffness_per_kg_and_restitution_to_a_damping_ratio():
    step = 0.005
    assert contact_solref(None, 0.03, step) == (stiff_solref(step),) * 2
    geom, pair = contact_solref(ContactState(100.0, 2.0), 0.05, step)
    assert geom == pair == (-2000.0, -40.0)
    # no bounce is the default contact's critical damping; a bounce of e: ratio 0.2155
    assert bouncing_solref(0.0, step) == pytest.approx((-1e4, -200.0))
    ratio = -math.log(0.5) / math.sqrt(math.pi ** 2 + math.log(0.5) ** 2)
    assert bouncing_solref(0.5, step)[1] == pytest.approx(-200.0 * ratio)
    geom, pair = contact_solref(ContactState(restitution=0.5), 0.03, step)
    assert geom == stiff_solref(step) and pair == bouncing_solref(0.5, step)


def test_the_preview_lists_each_worlds_draw_and_check_shows_it():
    task = task_with({'engine': 'pybullet', 'contact': SOFT}, worlds=2)
    summary = preview(task)
    drawn = [world.contact for world in world_states(task)]
    assert [entry['contact'] for entry in summary['worlds']] == [
        {'stiffness': c.stiffness, 'damping': c.damping} for c in drawn]
    text = worlds_text(summary)
    assert 'draws its contact (physics.contact): stiffness (N/m), damping (N s/m)' in text
    assert f'{drawn[1].stiffness:.4g}' in text
    assert 'contact' not in preview(task_with({}, worlds=2))['worlds'][0]
