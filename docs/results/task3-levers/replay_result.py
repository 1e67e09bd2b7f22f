"""
Replay a campaign's design from its result file: what the hand does, world by world.

A campaign commits each run's result (`result-KEY-seedN.json`: the best design by gene name)
and the task it ran (`tasks/KEY.yaml`), not its bag. This re-simulates that design in the
nominal world or an unseen one, in the task's engine, and prints every `--every` seconds:
where the object is, its turn about the vertical since the start (core.rotations.vertical_turn),
which of the hand's links touch it ('finger.joint', or the palm) and which joints rest on a
limit; then its final errors, and optionally a strip of frames of the rollout (PyBullet).

Usage (from the repository's root):
    python docs/results/task3-levers/replay_result.py TASK.yaml RESULT.json \
        [--every 0.1] [--world K] [--unseen 100] [--picture OUT.png --times 0 0.5 1 2]
"""

import argparse
import json
import sys

from hand_codesign.core.evaluate import evaluate_design
from hand_codesign.core.experiments.measures import measure_worlds, unseen_world_states
from hand_codesign.core.experiments.robustness import start_and_goal_poses
from hand_codesign.core.rotations import vertical_turn
from hand_codesign.core.sim.worlds import WorldState
from hand_codesign.core.task import TaskError
from hand_codesign.core.task.genome import genome_spec
from hand_codesign.core.task.reader import load_task
import numpy as np
from scipy.stats import spearmanr

WORLD_QUANTITIES = ('position_x', 'position_y', 'position_z', 'orientation_delta',
                    'friction_delta', 'scale', 'mass_factor')

# a joint within this of a limit (rad) rests on it
ON_LIMIT = 0.02


def recorded_design(task, result):
    """Return the Design of a result file's {gene name: value} on the task it ran."""
    spec = genome_spec(task)
    return spec.decode(spec.encode(result['design']))


def joint_names(design):
    """Return 'finger.joint' for every joint, in the simulator's joint order."""
    return [f'{f}.{j}' for f, finger in enumerate(design.hand.fingers)
            for j in range(len(finger.joints))]


def resting_on_limits(design, angles):
    """Return the names of the joints within ON_LIMIT of one of their limits."""
    joints = [joint for finger in design.hand.fingers for joint in finger.joints]
    return [name for name, joint, angle in zip(joint_names(design), joints, angles)
            if joint.lower_limit is not None
            and min(abs(angle - joint.lower_limit), abs(angle - joint.upper_limit)) < ON_LIMIT]


def trace(task, design, every, world):
    """Return the evaluation and rows (t, position, turn since start, touching, on limits)."""
    names = joint_names(design)
    rows, start = [], []

    def on_frame(step, simulator):
        position, orientation = simulator.object_pose()
        if not start:
            start.append(orientation)
        turn = vertical_turn(start[0], orientation)
        touching = sorted(simulator.touching_links(1e-3))
        rows.append((step * task.time_step, position, turn,
                     ['palm' if link < 0 else names[link] for link in touching],
                     resting_on_limits(design, simulator.joint_angles())))
    steps = max(1, int(round(every / task.time_step)))
    evaluation = evaluate_design(design, task, [world], on_frame=on_frame, frame_every=steps)
    return evaluation, rows


def unseen_turns(task, design, count):
    """
    Return (worlds, turns, touched) on `count` unseen worlds of the task's ranges.

    turns: (count,) rad, the object's turn about the vertical from its start to the end of the
    rollout (core.rotations.vertical_turn), NaN in a world the design starts in collision
    with; touched: (count,) bool, a link of a finger (not the palm) touched it at some frame.
    """
    worlds = unseen_world_states(task, count)
    turns, touched = turns_in_worlds(task, design, worlds)
    return worlds, turns, touched


def turns_in_worlds(task, design, worlds):
    """Return (turns, touched) of unseen_turns on the given worlds, whole motions."""
    measures = measure_worlds(genome_spec(task).encode(design), task, worlds)
    starts = start_and_goal_poses(task, worlds)[0]
    turns = np.array([np.nan if collided else vertical_turn(start[3:], end)
                      for start, end, collided in zip(starts, measures.final_orientations,
                                                      measures.collisions)])
    return turns, measures.touched & ~measures.collisions


def picture(task, design, world, path, times, view=(20, -70), distance=0.3):
    """Write a strip of frames of one world's rollout at `times` (s) to path."""
    from hand_codesign.analysis.replay import FrameGrabber, frame_every, FRAMES_PER_SECOND
    from hand_codesign.core.sim.pybullet_sim import Simulator
    from PIL import Image
    grabber = FrameGrabber(task, view)
    grabber.distance = distance  # m: the whole capsule and hand in view
    with Simulator(rendering=True) as simulator:
        evaluate_design(design, task, [world], simulator=simulator,
                        on_frame=grabber, frame_every=frame_every(task))
    frames = grabber.frames
    picks = [frames[min(len(frames) - 1, int(round(t * FRAMES_PER_SECOND)))] for t in times]
    Image.fromarray(np.concatenate(picks, axis=1)).save(path)


def main():
    """Replay the design and print what it does; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('task', help='the task file the campaign ran (its tasks/KEY.yaml)')
    parser.add_argument('result', help="the run's result file (result-KEY-seedN.json)")
    parser.add_argument('--every', type=float, default=0.1, help='seconds between rows')
    parser.add_argument('--world', type=int,
                        help='trace unseen world K (0-based) instead of the nominal one')
    parser.add_argument('--unseen', type=int, default=0,
                        help='also measure the turn on this many unseen worlds')
    parser.add_argument('--picture', help='write a strip of frames of the rollout here')
    parser.add_argument('--times', type=float, nargs='+', default=[0.0, 0.5, 1.0, 2.0])
    arguments = parser.parse_args()
    if arguments.world is not None and arguments.world < 0:
        parser.error(f'--world: expected a world index >= 0, got {arguments.world}')
    try:
        task = load_task(arguments.task).replace(early_termination=None)
        design = recorded_design(task, read_result(arguments.result))
    except (TaskError, OSError, ValueError) as error:
        print(f'replay_result: {error}', file=sys.stderr)
        return 2
    describe(design)
    world = (WorldState.nominal() if arguments.world is None
             else unseen_world_states(task, arguments.world + 1)[arguments.world])
    evaluation, rows = trace(task, design, arguments.every, world)
    for t, position, turn, touching, limits in rows:
        print(f't {t:4.2f}  object {np.round(position, 3).tolist()}  turned {turn:+.3f} rad  '
              f'touching {touching or "-"}  on a limit {limits or "-"}')
    print('final errors (m, rad):', np.round(evaluation.final_errors[0], 4).tolist(),
          'start collision' if evaluation.collision else '')
    if arguments.unseen:
        report_unseen(task, design, arguments.unseen)
    if arguments.picture:
        picture(task, design, world, arguments.picture, arguments.times)
        print('picture', arguments.picture, 'at', arguments.times, 's')
    return 0


def read_result(path):
    """Return a result file's contents; ValueError naming it when it holds no design."""
    with open(path, encoding='utf-8') as file:
        try:
            result = json.load(file)
        except json.JSONDecodeError as error:
            raise ValueError(f'{path}: not JSON ({error})') from None
    if not isinstance(result, dict) or not isinstance(result.get('design'), dict):
        raise ValueError(f'{path}: expected a result file with a "design" mapping')
    return result


def describe(design):
    """Print each finger's place, segments and joints."""
    for finger, values in enumerate(design.hand.fingers):
        print(f'finger {finger} at {np.round(values.position, 3).tolist()}, segments '
              f'{np.round(values.segment_lengths, 3).tolist()} m, joints '
              + '; '.join(f'axis {joint.axis_angle:+.2f} start {joint.initial_angle:+.2f} '
                          + limits_text(joint) for joint in values.joints))


def limits_text(joint):
    """Return 'limits [lower, upper]' of a joint (rad), or 'no limits'."""
    if joint.lower_limit is None:
        return 'no limits'
    return f'limits [{joint.lower_limit:+.2f}, {joint.upper_limit:+.2f}]'


def report_unseen(task, design, count):
    """Print the turn on `count` unseen worlds and its rank correlation with each quantity."""
    worlds, turns, touched = unseen_turns(task, design, count)
    collided = np.isnan(turns)
    if collided.all():
        print(f'{count} unseen worlds: the design starts in collision in every one')
        return
    print(f'{count} unseen worlds: turn median {np.nanmedian(turns):+.3f} rad, '
          f'p10 {np.nanpercentile(turns, 10):+.3f}, p90 {np.nanpercentile(turns, 90):+.3f}; '
          f'a finger touched it in {np.mean(touched[~collided]):.0%} of those simulated; the '
          f'design starts in collision in {np.mean(collided):.0%} (not simulated)')
    values = np.array([[*w.position_delta, w.orientation_delta, w.friction_delta, w.scale,
                        w.mass_factor] for w in worlds])
    print('rank correlation of the turn with each randomized quantity: ' + ', '.join(
        f'{name} {spearmanr(values[:, i], turns, nan_policy="omit")[0]:+.2f}'
        for i, name in enumerate(WORLD_QUANTITIES) if np.ptp(values[:, i]) > 0))


if __name__ == '__main__':
    sys.exit(main())
