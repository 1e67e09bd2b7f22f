"""
Rules of a task that span several keys, checked after reading and after Task.replace.

Each raises TaskError naming the key to fix.
"""

import math

from hand_codesign.core.task.descriptors import default_descriptors, descriptor_ranges
from hand_codesign.core.task.parts import (ALGORITHMS, ArchiveSpec, ENGINES,
                                           MORPHOLOGY_PARAMETERS, QD_ALGORITHMS,
                                           RESTART_ALGORITHMS, resting_height,
                                           RESTING_TOLERANCE, TaskError)
import numpy as np


def check_task(task):
    """Check what spans several keys; raise TaskError naming the key to fix."""
    source = task.source

    def fail(key, expected):
        raise TaskError(f'{source}: {key}: expected {expected}')

    for name in ('seed', 'iterations', 'population', 'num_world_states'):
        value = getattr(task, name)
        minimum = 0 if name == 'seed' else 1
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) \
                or value < minimum:
            key = {'seed': 'seed', 'num_world_states': 'world_states'}.get(name)
            fail(key or f'optimizer.{name}',
                 f'an integer >= {minimum}, got {value!r}')
    if not task.structure or any(int(j) < 1 for j in task.structure):
        fail('hand.structure', f'a non-empty list of positive joint counts, got '
             f'{task.structure!r}')
    if task.algorithm not in ALGORITHMS:
        fail('optimizer.algorithm', f'one of {", ".join(ALGORITHMS)}, got {task.algorithm!r}')
    if task.restart_stagnation is not None and task.algorithm not in RESTART_ALGORITHMS:
        fail('optimizer.restart_stagnation', f'no restart_stagnation for {task.algorithm} (it '
             f'is for {" and ".join(RESTART_ALGORITHMS)}, which restart CMA-ES)')
    if task.front_choice != 'normalized' and task.algorithm != 'mocma':
        fail('optimizer.front_choice', f'no front_choice for {task.algorithm} (it chooses a '
             'design of the Pareto front of mocma)')
    steps = task.duration / task.time_step
    if abs(steps - round(steps)) > 1e-6 or round(steps) < 1:
        fail('duration', f'a whole number of time steps ({task.time_step} s), got '
             f'{task.duration!r}')
    for kind in ('position', 'orientation'):
        for index, goal in enumerate(getattr(task.goals, kind)):
            if goal.time > task.duration + 1e-9:
                fail(f'goals.{kind}[{index}].time',
                     f'a time within the duration {task.duration} s, got {goal.time!r}')
    if task.policy.duration > task.duration + 1e-9:
        fail('policy.duration', f'at most the task duration {task.duration} s, got '
             f'{task.policy.duration!r}')
    if task.policy.kind == 'pd' and task.policy.keyframe_times[-1] > task.policy.duration:
        fail('policy.keyframe_times', f'times within policy.duration '
             f'{task.policy.duration} s, got {list(task.policy.keyframe_times)!r}')
    if task.policy.kind == 'torque' and task.policy.mode == 'interpolated' \
            and task.policy.knots < 2:
        fail('policy.knots', f'at least 2 knots to interpolate, got {task.policy.knots!r}')
    _check_object(task, fail)
    _check_settings(task, fail)
    if task.hierarchy is not None:
        _check_hierarchy(task.hierarchy, fail)
    _check_horizon(task, fail)
    _check_stages(task, fail)
    _check_worlds(task, fail)
    _check_archive(task, fail)
    _check_physics(task, fail)
    _check_contact(task, fail)


def _check_physics(task, fail):
    physics = task.physics
    if physics.engines[0] != physics.engine or len(set(physics.engines)) != len(
            physics.engines) or not set(physics.engines) <= set(ENGINES):
        fail('physics.engines', f'distinct engines of {", ".join(ENGINES)} led by physics.engine '
             f'{physics.engine!r}, got {list(physics.engines)!r}')


def _check_contact(task, fail):
    contact = task.physics.contact
    if contact is None:
        return
    if (contact.stiffness is None) != (contact.damping is None):
        given, missing = (('stiffness', 'damping') if contact.damping is None
                          else ('damping', 'stiffness'))
        fail(f'physics.contact.{missing}', f"a range beside {given} (Bullet's changeDynamics "
             "and MuJoCo's direct solref take stiffness and damping as a pair)")
    if 'mujoco' in task.physics.engines:
        _check_mujoco_contact(task, contact, fail)


def _check_mujoco_contact(task, contact, fail):
    # why: MuJoCo's only restitution is its contact's damping ratio (core.sim.mujoco_sim), so
    # a damping and a restitution would both set it; and its soft contact is stepped
    # explicitly: it stays stable only as stiff and damped as a time constant of two time
    # steps allows (MuJoCo's own floor), per kg of the object since MuJoCo's stiffness is an
    # acceleration per metre. The lightest object is the most demanding.
    if contact.damping is not None and contact.restitution is not None:
        fail('physics.contact.restitution', 'no restitution beside damping with mujoco in '
             "physics.engines (MuJoCo's restitution is its contact's damping: give one)")
    if contact.stiffness is None:
        return
    mass = task.object_spec.mass * task.randomization.mass.lower
    step = task.time_step
    for name, most in (('stiffness', mass / (2 * step) ** 2), ('damping', mass / step)):
        upper = getattr(contact, name).upper
        if upper > most:
            unit = 'N/m' if name == 'stiffness' else 'N s/m'
            fail(f'physics.contact.{name}', f'an upper end of at most {most:.6g} {unit} with '
                 f'mujoco in physics.engines (the most MuJoCo steps stably at time_step {step} '
                 f's for the lightest object, {mass:.6g} kg), got {upper:g}')


def _check_archive(task, fail):
    if task.algorithm not in QD_ALGORITHMS:
        if task.archive is not None:
            fail('optimizer.archive', f'no archive for {task.algorithm} (it is for '
                 f'{" and ".join(QD_ALGORITHMS)}, the quality-diversity searches)')
        return
    archive = task.archive or ArchiveSpec()
    if archive.learning_rate is not None and task.algorithm == 'cma-me':
        fail('optimizer.archive.learning_rate', 'no learning_rate for cma-me (its archive '
             'replaces an elite by any better design: a learning rate of 1); cma-mae takes one')
    if archive.emitters is not None and archive.emitters > task.population // 2:
        fail('optimizer.archive.emitters', f'at most population / 2 = {task.population // 2} '
             f'emitters (each samples at least 2 of the {task.population} candidates), got '
             f'{archive.emitters}')
    descriptor_ranges(task, archive.descriptors or default_descriptors(task))


def _check_worlds(task, fail):
    if task.worlds.resample != 'none':
        early = task.early_termination
        for present, what in ((task.hierarchy is not None, 'a hierarchy'),
                              (task.two_stage, 'two stages'),
                              (early is not None and early.horizon is not None, 'a horizon')):
            if present:
                fail('worlds.resample', f'none in a task with {what} (not supported: the '
                     'final check of resampled generations assumes one optimization on full '
                     f'rollouts), got {task.worlds.resample!r}')
    if task.worlds.racing is not None:
        _check_racing(task, fail)
    draw = task.world_draw
    if isinstance(draw, bool) or not isinstance(draw, (int, np.integer)) or draw < 0:
        fail('world_draw', f'an integer >= 0 (0: the fixed worlds), got {draw!r}')
    if draw and task.held_out:
        fail('world_draw', f'0 for the held-out worlds (one stream or the other), got {draw!r}')


def _check_racing(task, fail):
    # why: the race's bound ranks by the weighted sum and its mean over worlds, and the update
    # must be able to leave the candidates it stopped out (core.search.racing)
    if task.algorithm != 'cma':
        fail('worlds.racing', f'no racing with optimizer.algorithm {task.algorithm} (racing '
             'selects the mu best of a CMA-ES generation by their weighted sum: cma only)')
    if task.worlds.aggregate != 'mean':
        fail('worlds.racing', 'no racing with aggregate: worst (its bound is on the mean over '
             'the worlds, eq. 5)')
    if len(task.physics.engines) > 1:
        fail('worlds.racing', 'no racing with several physics.engines (its bound is on one '
             f"engine's worlds), got {list(task.physics.engines)!r}: drop one or racing")


def _check_stages(task, fail):
    if task.two_stage and task.hierarchy is not None:
        fail('two_stage', 'no two stages in a task with a hierarchy (not supported: its '
             'structures are compared on the randomized worlds)')
    if task.stage not in ((0, 1, 2) if task.two_stage else (0,)):
        fail('stage', f'{"0, 1 or 2" if task.two_stage else "0 (two_stage is off)"}, got '
             f'{task.stage!r}')


def _check_object(task, fail):
    spec = task.object_spec
    if spec.start == 'plane':
        height = resting_height(spec)
        if abs(spec.position[2] - height) > RESTING_TOLERANCE:
            fail('object.position', f'z = {height:.6g} for an object resting on the plane, '
                 f'got {spec.position[2]!r}')
        if task.randomization.position[2].width > 0:
            fail('randomization.position.z', '[0, 0] for an object starting on the plane, '
                 f'got [{task.randomization.position[2].lower}, '
                 f'{task.randomization.position[2].upper}]')
    if spec.friction + task.randomization.friction.lower < 0:
        fail('randomization.friction', 'deltas that keep the object friction >= 0, got '
             f'a lower delta of {task.randomization.friction.lower!r}')


def _settings(task):
    """Yield (dotted key, ParameterSpec) of every parameter setting of the task."""
    for name in MORPHOLOGY_PARAMETERS:
        yield f'morphology.{name}', getattr(task.morphology, name)
    for name in ('torque', 'target', 'kp', 'kd'):
        setting = getattr(task.policy, name)
        if setting is not None:
            yield f'policy.{name}', setting


def _check_settings(task, fail):
    fingers = len(task.structure)
    seed = task.seed_design
    if seed is not None and seed.hand.structure != task.structure:
        fail('hand.structure', f"the seed design's structure {list(seed.hand.structure)}, "
             f'got {list(task.structure)}')
    if seed is not None and seed.controller.kind != task.policy.kind \
            and any(s.mode in ('delta', 'seed') for k, s in _settings(task)
                    if k.startswith('policy.')):
        fail('seed_design.controller.kind', f'{task.policy.kind} for a policy set from the '
             f'seed, got {seed.controller.kind!r}')
    if seed is not None and seed.controller.kind == task.policy.kind \
            and len(seed.controller.values) != task.policy.num_knots:
        fail('seed_design.controller.values', f'{task.policy.num_knots} rows (the '
             f"policy's knots), got {len(seed.controller.values)}")
    for key, setting in _settings(task):
        if setting.mode in ('delta', 'seed') and seed is None:
            fail(key, 'a seed_design for a delta or seed setting (or use fixed or bounds)')
        if setting.mode in ('fixed', 'bounds') and len(setting.values) > 1 \
                and len(setting.values) < fingers:
            fail(key, f'one entry per finger ({fingers}), got {len(setting.values)}')
        if setting.mode == 'fixed':
            for finger, joints in enumerate(task.structure):
                entry = setting.entry(finger) if finger < len(setting.values) or \
                    len(setting.values) == 1 else None
                if isinstance(entry, tuple) and len(entry) != joints:
                    fail(key, f'{joints} values for finger {finger} (one per joint), got '
                         f'{len(entry)}')
        if setting.per_finger_total and key != 'morphology.segment_length':
            fail(key, 'per_finger_total only for segment_length')
    length = task.morphology.segment_length
    if length.mode == 'bounds' and any(b.lower <= 0 for b in length.values):
        fail('morphology.segment_length.bounds', 'positive lengths')


def _check_horizon(task, fail):
    early = task.early_termination
    if early is not None and early.horizon is not None and task.hierarchy is not None:
        fail('early_termination.horizon', 'no horizon in a task with a hierarchy (not '
             'supported: its structure checks compare full rollouts)')
    horizon = task.horizon
    if horizon is None:
        return
    if isinstance(horizon, bool) or not isinstance(horizon, (int, float)) \
            or not math.isfinite(horizon) or horizon <= 0:
        fail('horizon', f'a positive number of seconds, got {horizon!r}')
    if early is None:
        fail('horizon', f'early_termination to evaluate a horizon ({horizon!r} s): its '
             'margins charge the goals after it')


def _check_hierarchy(hierarchy, fail):
    if hierarchy.stop_structure is None and hierarchy.max_fingers is None:
        fail('hierarchy', 'stop_structure or max_fingers to end the search')
    if hierarchy.max_fingers is not None and len(hierarchy.start) > hierarchy.max_fingers:
        fail('hierarchy.start', f'at most max_fingers ({hierarchy.max_fingers}) fingers')
