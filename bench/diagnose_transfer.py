"""
Why a PyBullet design does what it does in MuJoCo: the same design and world in both engines.

Modes on a campaign's committed design (`result-RUN.json`, whose task and genome
campaign.measures.result_design rebuilds):

- `worlds`: the final turn error (or, with --kind, the error in the plane or along an axis,
  within Task 5's 5 mm) of each unseen world in both engines (and, with
  --pre-com-fix, in MuJoCo with the object's centre of mass where it sat before the fix:
  the body's start offset from the origin once more, on the box's top face), the cross table
  of within / not within 0.1 rad, and the worlds that succeed in PyBullet and fail in MuJoCo
  with their mass, scale and friction.
- `trace WORLD`: per step, side by side, the box's position, yaw, tilt (rad between its z axis
  and the vertical), the joint angles and which rest on a limit, and the contacts (which
  bodies touch, their summed normal force); and where the rollouts first diverge.
- `gif WORLD --out FILE`: the rollout in PyBullet (left) and MuJoCo (right), one GIF.
- `impacts --errors FILE`: on the worlds of `worlds --save FILE` that succeed in PyBullet only
  (and on 40 where both succeed), each engine's first finger contact: the box's turn over the
  next 5 steps, its largest tilt and lift over the next 20, and the medians.
- `slide`: Task 5's box launched along the ground at --speed m/s, nothing else touching it:
  how high it rises in each engine (MuJoCo's convex contact model lifts a sliding body) and
  how far it slides.
- `drop`: Task 5's box moving down at --speed m/s from --gap mm above the ground: how much of
  its approach speed each engine gives back when it lands (Bullet's hard contact none;
  MuJoCo's soft contact pushes the penetration of the landing step back out).

In every mode, --damping-ratio R runs MuJoCo with every contact's and joint limit's damping
ratio at R instead of 1 (a probe, not a setting: the higher, the less a contact that built up
within a step kicks back, and the softer it is).

Usage: python bench/diagnose_transfer.py worlds RESULT.json [--preset P] [--unseen 1000]
       [--pre-com-fix] [--kind orientation|plane|x|y] [--damping-ratio R]
       python bench/diagnose_transfer.py trace RESULT.json WORLD [--every 10]
       python bench/diagnose_transfer.py gif RESULT.json WORLD --out FILE.gif
       python bench/diagnose_transfer.py impacts RESULT.json --errors FILE
       python bench/diagnose_transfer.py slide - [--speed 0.4]
       python bench/diagnose_transfer.py drop - [--speed 0.4] [--gap 5]
"""

import argparse
import contextlib
import dataclasses
import json
import math
import pathlib

from hand_codesign.analysis.replay import render_frames
from hand_codesign.campaign.measures import result_design
from hand_codesign.core import load_task
from hand_codesign.core.design import FingerDesign, JointDesign
from hand_codesign.core.evaluate import evaluate_design
from hand_codesign.core.experiments.measures import measure_worlds, start_and_goal_poses
from hand_codesign.core.experiments.measures import unseen_world_states
from hand_codesign.core.outcomes import CONTACT_DISTANCE, LIMIT_TOLERANCE
from hand_codesign.core.sim import mujoco_sim
from hand_codesign.core.sim.hand import hand_model
from hand_codesign.core.sim.mujoco_sim import MujocoSimulator
from hand_codesign.core.sim.pybullet_sim import Simulator
from hand_codesign.core.sim.worlds import object_state, WorldState
from hand_codesign.core.task.genome import genome_spec
import mujoco
import numpy as np

TURN_LIMIT = 0.1  # rad
# the error kinds `worlds --kind` compares, each with its task's tolerance and unit
LIMITS = {'orientation': TURN_LIMIT, 'plane': 0.005, 'x': 0.005, 'y': 0.005}
UNITS = {'orientation': 'rad', 'plane': 'mm', 'x': 'mm', 'y': 'mm'}
SLIDE_STEPS = 40
IMPACT_STEPS = 20  # steps after a first finger contact in which its tilt and lift are read


@contextlib.contextmanager
def pre_com_fix():
    """Put MuJoCo's object centre of mass and inertia axes back where they were before the fix."""
    original = MujocoSimulator._load_world

    def load_world(self, state, shape):
        loaded = self._loaded == (state, shape)
        original(self, state, shape)
        if not loaded:
            m, body = self.mj_model, self._object_body
            m.body_ipos[body] = state.position
            m.body_iquat[body] = mujoco_sim._wxyz(state.orientation)
            m.body_sameframe[body] = m.body_simple[body] = 0  # its frames now differ
            mujoco.mj_setConst(m, self.mj_data)
    MujocoSimulator._load_world = load_world
    try:
        yield
    finally:
        MujocoSimulator._load_world = original


def design_and_tasks(result_path, preset):
    """Return (x, {engine: task}) of a result file."""
    result = json.loads(pathlib.Path(result_path).read_text())
    tasks = {}
    for engine in ('pybullet', 'mujoco'):
        task, x = result_design(result, preset, engine)
        tasks[engine] = task
    return x, tasks


def worlds_mode(arguments):
    x, tasks = design_and_tasks(arguments.result, arguments.preset)
    worlds = unseen_world_states(tasks['pybullet'], arguments.unseen)
    kind, limit, unit = arguments.kind, LIMITS[arguments.kind], UNITS[arguments.kind]
    scale = 1000 if unit == 'mm' else 1
    measured = {engine: measure_worlds(x, task, worlds) for engine, task in tasks.items()}
    if arguments.pre_com_fix:
        with pre_com_fix():
            measured['mujoco-pre-fix'] = measure_worlds(x, tasks['mujoco'], worlds)
    errors = {engine: measures.errors[kind] for engine, measures in measured.items()}
    for name, measures in measured.items():
        values = errors[name]
        print(f'{name}: within {np.mean(values < limit):.1%}, median '
              f'{np.median(values) * scale:.3f} {unit}, p90 '
              f'{np.percentile(values, 90) * scale:.3f} {unit}; ends on a limit touching the '
              f'box in {np.mean(measures.limit_contacts):.1%}')
    bullet, other = errors['pybullet'] < limit, errors['mujoco'] < limit
    print(f'both within {np.mean(bullet & other):.1%}, PyBullet only '
          f'{np.mean(bullet & ~other):.1%}, MuJoCo only {np.mean(~bullet & other):.1%}, '
          f'neither {np.mean(~bullet & ~other):.1%}')
    lost = bullet & ~other
    if unit == 'mm':  # a position error: where the box ends, signed, along each axis
        goals = np.asarray(start_and_goal_poses(tasks['pybullet'], worlds)[1])[:, :2]
        for axis, column in (('x', 0), ('y', 1)):
            signed = {engine: (measured[engine].final_positions[:, column] - goals[:, column])
                      * 1000 for engine in ('pybullet', 'mujoco')}
            print(f'  along {axis}, signed offset from the goal, median (mm) PyBullet / MuJoCo: '
                  f'all worlds {np.median(signed["pybullet"]):+.2f} / '
                  f'{np.median(signed["mujoco"]):+.2f}; worlds PyBullet only '
                  f'{np.median(signed["pybullet"][lost]):+.2f} / '
                  f'{np.median(signed["mujoco"][lost]):+.2f}')
    indices = np.flatnonzero(lost)
    order = indices[np.argsort(-errors['mujoco'][indices])]
    print(f'PyBullet within, MuJoCo not (worst first): world, {kind} error PyBullet, MuJoCo '
          f'({unit}), mass factor, scale, friction')
    for index in order[:arguments.show]:
        world = worlds[index]
        print(f'  {index:4d} {errors["pybullet"][index] * scale:.3f} '
              f'{errors["mujoco"][index] * scale:.3f} {world.mass_factor:.3f} '
              f'{world.scale:.3f} {world.friction_delta:+.3f}')
    if arguments.save:
        pathlib.Path(arguments.save).write_text(json.dumps(
            {name: values.tolist() for name, values in errors.items()}
            | {'kind': kind, 'limit': limit}) + '\n')


def _yaw_tilt(quaternion):
    """Return (yaw about the vertical, tilt of the body's z axis) of a quaternion x, y, z, w."""
    x, y, z, w = quaternion
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    tilt = math.acos(max(-1.0, min(1.0, 1 - 2 * (x * x + y * y))))
    return yaw, tilt


def _bullet_contacts(simulator):
    client, hand, thing = simulator.client, simulator.hand, simulator.object_body
    names = {simulator.ground: 'ground', hand: 'hand', thing: 'box'}
    forces = {}
    for point in client.getContactPoints():
        a, b = names.get(point[1], '?'), names.get(point[2], '?')
        a = f'L{point[3]}' if a == 'hand' else a
        b = f'L{point[4]}' if b == 'hand' else b
        if point[8] > CONTACT_DISTANCE:
            continue  # a speculative point farther than a touch
        key = '-'.join(sorted((a, b)))
        forces[key] = forces.get(key, 0.0) + point[9]
    return forces


def _mujoco_contacts(simulator):
    m, d = simulator.mj_model, simulator.mj_data
    palm = simulator._palm_body
    force = np.zeros(6)
    forces = {}
    for index in range(d.ncon):
        contact = d.contact[index]
        if contact.efc_address < 0:
            continue  # within the touch margin, not acting
        names = []
        for geom in contact.geom:
            if geom == simulator._ground_geom:
                names.append('ground')
            elif geom == simulator._object_geom:
                names.append('box')
            else:
                names.append(f'L{int(m.geom_bodyid[geom]) - palm - 1}')
        mujoco.mj_contactForce(m, d, index, force)
        key = '-'.join(sorted(names))
        forces[key] = forces.get(key, 0.0) + float(force[0])
    return forces


def trace(engine, task, x, world):
    """Return [(step, row dict)] of one world's rollout in one engine."""
    design = genome_spec(task).decode(x)
    links = None
    rows = []

    def frame(step, simulator):
        nonlocal links
        links = simulator.model.links
        position, orientation = simulator.object_pose()
        yaw, tilt = _yaw_tilt(orientation)
        angles = simulator.joint_angles()
        limits = ''.join(
            'L' if angle <= link.lower_limit + LIMIT_TOLERANCE
            else 'U' if angle >= link.upper_limit - LIMIT_TOLERANCE else '.'
            for link, angle in zip(links, angles))
        contacts = (_bullet_contacts if engine == 'pybullet' else _mujoco_contacts)(simulator)
        rows.append((step, {'position': position, 'yaw': yaw, 'tilt': tilt, 'angles': angles,
                            'limits': limits, 'contacts': contacts}))
    simulator = Simulator() if engine == 'pybullet' else MujocoSimulator()
    with simulator:
        evaluate_design(design, task, [world], simulator=simulator, on_frame=frame,
                        frame_every=1)
    return rows, design


def trace_mode(arguments):
    x, tasks = design_and_tasks(arguments.result, arguments.preset)
    world = unseen_world_states(tasks['pybullet'], arguments.unseen)[arguments.world]
    print(f'world {arguments.world}: mass factor {world.mass_factor:.3f}, scale '
          f'{world.scale:.3f}, friction {world.friction_delta:+.3f}, start yaw '
          f'{world.orientation_delta:+.3f}')
    traces = {}
    for engine, task in tasks.items():
        traces[engine] = trace(engine, task, x, world)[0]
    first = {}
    for (step, bullet), (_, other) in zip(traces['pybullet'], traces['mujoco']):
        checks = {'yaw 0.01 rad': abs(bullet['yaw'] - other['yaw']) > 0.01,
                  'position 1 mm': math.dist(bullet['position'], other['position']) > 1e-3,
                  'tilt 0.01 rad': abs(bullet['tilt'] - other['tilt']) > 0.01,
                  'joints 0.01 rad': max(abs(a - b) for a, b
                                         in zip(bullet['angles'], other['angles'])) > 0.01,
                  'touching pairs': set(bullet['contacts']) != set(other['contacts'])}
        for name, differs in checks.items():
            if differs and name not in first:
                first[name] = step
        if step % arguments.every == 0 or step in first.values():
            for engine, row in (('PB', bullet), ('MJ', other)):
                contacts = ' '.join(f'{key}:{value:.3f}' for key, value
                                    in sorted(row['contacts'].items()))
                print(f'{step:3d} {engine} z {row["position"][2] * 1000:6.2f} mm xy '
                      f'{row["position"][0] * 1000:+6.1f} {row["position"][1] * 1000:+6.1f} '
                      f'yaw {row["yaw"]:+.3f} tilt {row["tilt"]:.3f} q '
                      f'{" ".join(f"{a:+.3f}" for a in row["angles"])} {row["limits"]} | '
                      f'{contacts}')
    print('first divergence (step):', first)


def gif_mode(arguments):
    import imageio.v3 as imageio
    x, tasks = design_and_tasks(arguments.result, arguments.preset)
    world = unseen_world_states(tasks['pybullet'], arguments.unseen)[arguments.world]

    class Recorded:
        pass
    recorded = Recorded()
    recorded.x = x
    frames = [render_frames(tasks[engine], recorded, world, (0.0, -60.0))
              for engine in ('pybullet', 'mujoco')]
    count = min(len(part) for part in frames)
    joined = np.stack([np.concatenate((frames[0][index], frames[1][index]), axis=1)
                       for index in range(count)])
    imageio.imwrite(arguments.out, joined, extension='.gif', duration=40, loop=0)
    print(f'wrote {arguments.out} ({count} frames, PyBullet left, MuJoCo right)')


def first_hit(rows):
    """Return the index of the first step with a finger (not the palm) touching the box."""
    for index, (_, row) in enumerate(rows):
        if any(key.startswith('L') and not key.startswith('L-') and 'box' in key
               for key in row['contacts']):
            return index
    return None


def impact(rows):
    """Return (step, turn over 5 steps, largest tilt and lift (m) over 20) of a trace's hit."""
    index = first_hit(rows)
    if index is None:
        return None
    after = [row for _, row in rows[index:index + IMPACT_STEPS]]
    start = rows[max(index - 1, 0)][1]
    return (rows[index][0], rows[min(index + 5, len(rows) - 1)][1]['yaw'] - start['yaw'],
            max(row['tilt'] for row in after),
            max(row['position'][2] for row in after) - rows[0][1]['position'][2])


def impacts_mode(arguments):
    x, tasks = design_and_tasks(arguments.result, arguments.preset)
    worlds = unseen_world_states(tasks['pybullet'], arguments.unseen)
    errors = json.loads(pathlib.Path(arguments.errors).read_text())
    limit = errors.get('limit', TURN_LIMIT)
    bullet = np.array(errors['pybullet']) < limit
    other = np.array(errors['mujoco']) < limit
    groups = {'PyBullet within, MuJoCo not': np.flatnonzero(bullet & ~other),
              'both within (first 40)': np.flatnonzero(bullet & other)[:40]}
    for name, indices in groups.items():
        hits = []
        for index in indices:
            found = [impact(trace(engine, tasks[engine], x, worlds[index])[0])
                     for engine in ('pybullet', 'mujoco')]
            if None not in found:
                hits.append(found[0][1:] + found[1][1:])
        values = np.array(hits)
        same = int(np.sum(np.sign(values[:, 0]) == np.sign(values[:, 3])))
        print(f'{name}: {len(values)} worlds; turn over the 5 steps after the first finger '
              f'contact, median PyBullet {np.median(values[:, 0]):+.3f}, MuJoCo '
              f'{np.median(values[:, 3]):+.3f} rad (same direction in {same}, MuJoCo more '
              f'positive in {int(np.sum(values[:, 3] > values[:, 0]))}); largest tilt '
              f'{np.median(values[:, 1]):.3f} / {np.median(values[:, 4]):.3f} rad; largest lift '
              f'{np.median(values[:, 2]) * 1000:.2f} / {np.median(values[:, 5]) * 1000:.2f} mm')


def box_scene():
    """Return (task, hand model, nominal box state): Task 5's box, short fingers far above it."""
    task = load_task(pathlib.Path(__file__).resolve().parents[1] / 'config' / 'tasks'
                     / 'task5.yaml')
    base = genome_spec(task).decode(genome_spec(task).initial_mean())
    joints = (JointDesign(axis_angle=np.pi / 2, initial_angle=0.0, lower_limit=-1.2,
                          upper_limit=1.2),) * 2
    fingers = tuple(FingerDesign(position=(x, 0.0), segment_lengths=(0.04, 0.04), joints=joints)
                    for x in (-0.055, 0.055))
    hand = dataclasses.replace(base.hand, fingers=fingers)
    return task, hand_model(hand, task.hand), object_state(task, WorldState.nominal())


def launched(velocity, lift=0.0):
    """
    Return {engine: (positions (steps, 3) m, velocities (steps, 3) m/s)} of the free box.

    The box starts `lift` m above its resting pose with the linear `velocity` (m/s, world
    frame), nothing else touching it, and is stepped SLIDE_STEPS times in each engine.
    """
    task, model, state = box_scene()
    state = dataclasses.replace(state, position=np.asarray(state.position) + (0.0, 0.0, lift))
    paths = {}
    with Simulator() as simulator:
        simulator.build(task, model)
        body = simulator.create_object(state, simulator.object_shape(state, 'box'))
        client = simulator.client
        client.resetBaseVelocity(body, list(velocity), [0.0, 0.0, 0.0])
        rows = []
        for _ in range(SLIDE_STEPS):
            client.stepSimulation()
            rows.append((client.getBasePositionAndOrientation(body)[0],
                         client.getBaseVelocity(body)[0]))
        paths['pybullet'] = rows
    with MujocoSimulator() as simulator:
        simulator.build(task.replace(physics=dataclasses.replace(task.physics, engine='mujoco')),
                        model)
        simulator.reset(state, 'box')
        m, d = simulator.mj_model, simulator.mj_data
        linear = slice(simulator._joints, simulator._joints + 3)  # the free joint's x, y, z
        d.qvel[linear] = velocity
        rows = []
        for _ in range(SLIDE_STEPS):
            mujoco.mj_step(m, d)
            rows.append((simulator.object_pose()[0], d.qvel[linear].copy()))
        paths['mujoco'] = rows
    return {engine: (np.array([row[0] for row in rows]), np.array([row[1] for row in rows]))
            for engine, rows in paths.items()}


def slide_mode(arguments):
    _, _, state = box_scene()
    speed = arguments.speed
    coulomb = speed ** 2 / (2 * state.friction * 9.81) * 1000
    for engine, (positions, _) in launched((speed, 0.0, 0.0)).items():
        lift = (positions[:, 2] - state.position[2]) * 1000
        slid = (positions[-1, 0] - state.position[0]) * 1000
        print(f'{engine}: box launched at {speed} m/s (friction {state.friction}); over '
              f'{SLIDE_STEPS} steps its height above rest ranges {lift.min():+.3f} to '
              f'{lift.max():+.3f} mm; it slides {slid:.1f} mm (Coulomb friction at this '
              f'coefficient stops it after {coulomb:.1f} mm)')


def drop_mode(arguments):
    speed, gap = arguments.speed, arguments.gap / 1000
    for engine, (_, velocities) in launched((0.0, 0.0, -speed), gap).items():
        print(f'{engine}: box moving down at {speed} m/s from {arguments.gap} mm above the '
              f'ground: at most {velocities[:, 2].max():+.3f} m/s upward after it lands, '
              f'{velocities[:, 2].max() / speed:.2f} of the approach speed')


def main():
    """Run one mode."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('mode', choices=('worlds', 'trace', 'gif', 'impacts', 'slide', 'drop'))
    parser.add_argument('result')
    parser.add_argument('world', type=int, nargs='?', default=0)
    parser.add_argument('--preset', default='task6_palm_beside.yaml')
    parser.add_argument('--unseen', type=int, default=1000)
    parser.add_argument('--pre-com-fix', action='store_true')
    parser.add_argument('--kind', choices=tuple(LIMITS), default='orientation')
    parser.add_argument('--damping-ratio', type=float, default=0.0)
    parser.add_argument('--show', type=int, default=15)
    parser.add_argument('--save', default='')
    parser.add_argument('--every', type=int, default=10)
    parser.add_argument('--out', default='diagnose.gif')
    parser.add_argument('--speed', type=float, default=0.4)
    parser.add_argument('--gap', type=float, default=5.0)
    parser.add_argument('--errors', default='')
    arguments = parser.parse_args()
    if arguments.damping_ratio:
        # a probe, not a setting: every MuJoCo contact's and limit's damping ratio
        mujoco_sim.SOLREF_DAMPING_RATIO = arguments.damping_ratio
    {'worlds': worlds_mode, 'trace': trace_mode, 'gif': gif_mode, 'impacts': impacts_mode,
     'slide': slide_mode, 'drop': drop_mode}[arguments.mode](arguments)


if __name__ == '__main__':
    main()
