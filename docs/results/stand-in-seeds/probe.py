"""Probe a preset's seed design: nominal rollout trace, corner start collisions, unseen worlds."""
import itertools
import sys

import numpy as np

from hand_codesign.core.evaluate import evaluate_design, shared_simulator
from hand_codesign.core.experiments.measures import unseen_world_states
from hand_codesign.core.sim.hand import hand_model
from hand_codesign.core.sim.worlds import WorldState, object_state
from hand_codesign.core.task.genome import genome_spec, seed_genome
from hand_codesign.core.task.reader import load_task


def seed_design(task):
    return genome_spec(task).decode(seed_genome(task))


def nominal_trace(task, every=20):
    design = seed_design(task)
    rows = []

    def on_frame(step, sim):
        pos, orn = sim.object_pose()
        pts = sim.client.getContactPoints(sim.hand, sim.object_body)
        links = sorted({p[3] for p in pts if p[8] <= 1e-3})
        rows.append((step * task.time_step, pos[2], pos[0], pos[1], links, 2 * np.arctan2(orn[2], orn[3])))
    ev = evaluate_design(design, task, [WorldState.nominal()], on_frame=on_frame, frame_every=every)
    return ev, rows


def corners(task):
    bounds = [b for _, b in task.randomization.quantities()]
    worlds = [WorldState.from_values(v) for v in
              itertools.product(*[(b.lower, b.lower + b.width) for b in bounds])]
    sim = shared_simulator(task.physics.engine)
    sim.build(task, hand_model(seed_design(task).hand, task.hand))
    bad = []
    for w in worlds:
        st = object_state(task, w)
        if sim.start_collisions([(st, sim.object_shape(st, task.object_spec.shape))]):
            bad.append(w)
    return len(worlds), bad


def unseen(task, count):
    design = seed_design(task)
    worlds = unseen_world_states(task, count)
    last = {}
    current = [0]

    def on_world(index, sim):
        current[0] = index

    def on_frame(step, sim):
        last[current[0]] = -1 in sim.touching_links(1e-3)
    every = int(round(task.duration / task.time_step)) // 4
    ev = evaluate_design(design, task, worlds, on_world=on_world, on_frame=on_frame,
                         frame_every=every)
    object.__setattr__(ev, "palm_at_end", np.array([last.get(i, False) for i in range(count)]))
    return ev


if __name__ == '__main__':
    task = load_task(sys.argv[1]).replace(early_termination=None)
    if len(sys.argv) > 3:
        import dataclasses
        task = task.replace(physics=dataclasses.replace(task.physics, engine=sys.argv[3]))
    start_z = task.object_spec.position[2]
    if task.physics.engine == 'pybullet':
        ev, rows = nominal_trace(task)
        for t, z, x, y, links, yaw in rows:
            print(f't {t:5.2f} z {z:.3f} (dz {z - start_z:+.3f}) x {x:+.3f} y {y:+.3f} yaw {yaw:+.3f} contacts {links}')
        print('nominal final errors (m, rad):', ev.final_errors[0], 'collision', ev.collision,
              'fitness', ev.fitness)
        n, bad = corners(task)
        print(f'corners with start collisions: {len(bad)} of {n}')
    count = int(sys.argv[2]) if len(sys.argv) > 2 else 0
    if count:
        ev = unseen(task, count)
        z = ev.final_poses[:, 2]
        o = ev.final_errors[:, 1]
        print(f'unseen {count}: collision {ev.collision} unstable {ev.unstable_worlds}; final z - start: '
              f'median {np.median(z - start_z):+.3f} min {np.min(z - start_z):+.3f}; '
              f'share within 5 cm of start height {np.mean(np.abs(z - start_z) < 0.05):.2f}; '
              f'orientation error median {np.median(o):.3f} rad, within 0.1 rad {np.mean(o < 0.1):.2f}; '
              f'dropped (z < start - 0.25 m) {np.mean(z - start_z < -0.25):.2f}; palm contact at the end {np.mean(getattr(ev, "palm_at_end", np.zeros(1))):.2f}; '
              f'position error median {np.median(ev.final_errors[:, 0]):.3f} m')


def picture(task, path, view=None, times=(0.0, 0.5, 1.0, 2.0), distance=4.0):
    """Write a strip of frames of the seed design's nominal rollout at `times` (s)."""
    from PIL import Image
    from hand_codesign.analysis.replay import FrameGrabber, frame_every, FRAMES_PER_SECOND
    from hand_codesign.core.sim.pybullet_sim import Simulator
    grabber = FrameGrabber(task, view or (30, -25))
    grabber.distance = distance
    with Simulator(rendering=True) as simulator:
        evaluate_design(seed_design(task), task, [WorldState.nominal()], simulator=simulator,
                        on_frame=grabber, frame_every=frame_every(task))
    frames = grabber.frames
    picks = [frames[min(len(frames) - 1, int(round(t * FRAMES_PER_SECOND)))] for t in times]
    Image.fromarray(np.concatenate(picks, axis=1)).save(path)
    print('picture', path, 'frames at', times)
