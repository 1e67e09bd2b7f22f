"""
`hand-codesign replay BAG [--generation G] [--rank K] [--world W] [--gif F | --gui | --mcap F]`.

Rebuilds one recorded design from the bag (default: the run's best; with --generation and
--rank the K-th best of generation G, 0 the best), re-simulates it with `core.evaluate` on the
run's task and world states, and checks that every objective, the fitness and every world's
objective equal the recorded ones bit for bit. A difference is reported loudly and the exit
code is 1: the run was made with another version of the code or libraries (the bag's RunInfo
lists the versions), or evaluation is not deterministic.

Then it shows world W: as an animated GIF rendered in DIRECT mode with the TinyRenderer from a
fixed camera (default file `<bag>_candidate<id>_world<W>.gif` next to the bag, or --gif), or
live in the PyBullet window with --gui (needs a display), or as a ROS 2 MCAP of markers for
Foxglove with --mcap (written by hand_codesign.commands.replay, which gives `write_mcap`:
writing messages is not this room's; `rollout_poses` here simulates what it draws).
"""

import os
import pathlib
import sys
import time

from hand_codesign.analysis import records
from hand_codesign.arithmetic import NATIVE
from hand_codesign.core.evaluate import evaluate
from hand_codesign.core.evaluate import evaluate_design
from hand_codesign.core.evaluate import new_simulator
from hand_codesign.core.experiments.motion import FRAMES_PER_SECOND as MOTION_FRAMES_PER_SECOND
from hand_codesign.core.experiments.motion import rollout_motion
from hand_codesign.core.sim.hand import hand_model
from hand_codesign.core.sim.pybullet_sim import object_shape
from hand_codesign.core.sim.pybullet_sim import Simulator
from hand_codesign.core.sim.worlds import object_state
from hand_codesign.core.sim.worlds import world_states
from hand_codesign.core.task.genome import genome_spec
from hand_codesign.errors import UserError
from hand_codesign.outputs import staged
import numpy as np

FRAMES_PER_SECOND = MOTION_FRAMES_PER_SECOND   # a robot model's /tf has the same frames
IMAGE_SIZE = (480, 360)
CAMERA_YAW = 0.0        # degrees: the camera looks along +y, across the fingers' x-z plane
CAMERA_PITCH = -20.0
HAND_COLOUR = (0.85, 0.55, 0.25, 1.0)
OBJECT_COLOUR = (0.2, 0.45, 0.85, 1.0)
GROUND_COLOUR = (0.8, 0.8, 0.8, 1.0)


def replay_command(arguments, write_mcap=None):
    """
    Replay one design of a bag; return 0, or 1 when the objectives differ.

    write_mcap(path, task, design, world) -> frames: writes the --mcap file, if asked for.
    """
    if getattr(arguments, 'mcap', None) and write_mcap is None:
        raise UserError('--mcap: this entry point cannot write MCAP files; run '
                        '`hand-codesign replay`')
    if arguments.gui and not has_display():
        raise UserError('--gui needs a display, and this session has none (DISPLAY is not '
                        'set); render an animation instead with --gif FILE')
    record = records.open_run(arguments.bag)
    design = chosen_design(record, arguments.generation, arguments.rank,
                           getattr(arguments, 'candidate', None))
    task = records.design_task(record, design)
    worlds = world_states(task)
    if not 0 <= arguments.world < len(worlds):
        raise UserError(f'--world {arguments.world}: the run has {len(worlds)} world states; '
                        f'expected 0 to {len(worlds) - 1}')
    horizon = f', horizon {design.horizon:g} s' if design.horizon else ''
    print(f'replaying candidate {design.candidate_id} of generation {design.generation} '
          f'(structure {list(design.structure)}{horizon}, evaluated by '
          f'{design.evaluator_id or "nobody in the bag"}) on {len(worlds)} world states')
    started = time.perf_counter()
    evaluation = evaluate(design.x, task)
    print(f're-simulated in {time.perf_counter() - started:.2f} s')
    same = report_comparison(design, evaluation)
    if arguments.gui:
        show_gui(task, design, worlds[arguments.world])
    elif getattr(arguments, 'mcap', None):
        frames = write_mcap(pathlib.Path(arguments.mcap), task, design, worlds[arguments.world])
        print(f'MCAP for Foxglove: {arguments.mcap} ({frames} frames of world '
              f'{arguments.world})')
    else:
        gif = pathlib.Path(arguments.gif) if arguments.gif else default_gif_path(
            record.path, design.candidate_id, arguments.world)
        frames = render_gif(gif, task, design, worlds[arguments.world],
                            getattr(arguments, 'camera', None))
        print(f'animation: {gif} ({frames} frames of world {arguments.world})')
    return 0 if same else 1


def chosen_design(record, generation, rank, candidate=None):
    """Return the RecordedDesign that the flags choose (candidate: an id, or None)."""
    if candidate is not None:
        if generation is not None or rank:
            raise UserError(f'--candidate {candidate} names one design: drop --generation and '
                            '--rank')
        return records.recorded_design(record, candidate)
    if generation is None and not rank:
        candidate_id = records.best_candidate_id(record)
    else:
        candidate_id = records.ranked_candidate_id(record, generation, rank)
    return records.recorded_design(record, candidate_id)


def default_gif_path(bag_path, candidate_id, world):
    """Return `<bag>_candidate<id>_world<W>.gif` next to the bag."""
    return records.beside_bag(bag_path, f'_candidate{candidate_id}_world{world}.gif')


def same_bits(first, second):
    """Return whether two float arrays hold the very same bits (NaN and -0.0 included)."""
    first = np.ascontiguousarray(first, dtype=np.float64)
    second = np.ascontiguousarray(second, dtype=np.float64)
    return first.shape == second.shape and np.array_equal(first.view(np.uint64),
                                                          second.view(np.uint64))


def compare(design, evaluation):
    """Return [(what, recorded, replayed, same)] for objectives, fitness and world values."""
    rows = [(name, recorded, replayed, same_bits(recorded, replayed))
            for name, recorded, replayed in zip(design.objective_names, design.objectives,
                                                evaluation.objectives)]
    if len(design.objectives) != len(evaluation.objectives):
        rows.append(('number of objectives', len(design.objectives),
                     len(evaluation.objectives), False))
    rows.append(('fitness', design.fitness, evaluation.fitness,
                 same_bits(design.fitness, evaluation.fitness)))
    if design.world_objectives is not None:
        recorded = design.world_objectives
        replayed = evaluation.world_objectives
        same = same_bits(recorded, replayed)
        differing = ('all equal' if same else
                     f'{int(np.sum(np.any(recorded != replayed, axis=1)))} of {len(recorded)} '
                     'worlds differ' if recorded.shape == replayed.shape else
                     f'shape {recorded.shape} vs {replayed.shape}')
        rows.append(('per-world objectives', differing, '', same))
    return rows


def report_comparison(design, evaluation):
    """Print the comparison with the recorded result; return whether it is bit-identical."""
    if design.objectives is None:
        print(f'warning: the bag holds no successful evaluation of candidate '
              f'{design.candidate_id}: nothing to compare; replayed objectives: '
              + ', '.join(f'{name} {value!r}' for name, value in
                          zip(evaluation.objective_names, evaluation.objectives)),
              file=sys.stderr)
        return True
    rows = compare(design, evaluation)
    width = max(len(what) for what, *_ in rows)
    print(f'{"":<{width}}  {"recorded":>24}  {"replayed":>24}')
    for what, recorded, replayed, same in rows:
        recorded_text = repr(float(recorded)) if isinstance(recorded, (float, np.floating)) \
            else str(recorded)
        replayed_text = repr(float(replayed)) if isinstance(replayed, (float, np.floating)) \
            else str(replayed)
        print(f'{what:<{width}}  {recorded_text:>24}  {replayed_text:>24}  '
              f'{"same" if same else "DIFFERENT"}')
    same = all(row[3] for row in rows)
    if same:
        print('replay reproduces the recorded objectives bit for bit')
    else:
        print('!' * 78 + '\nREPLAY MISMATCH: the re-simulated objectives differ from the ones '
              'recorded in the bag.\nThe run used other code or library versions (see the '
              'versions in its RunInfo), or evaluation is not deterministic.\nA run recorded '
              'on a processor with AVX-512 before the arithmetic was pinned replays with '
              f'{NATIVE}=1 on a processor of that kind.\n' + '!' * 78,
              file=sys.stderr)
    return same


# -------------------------------------------------------------------- rendering

def camera(task):
    """Return (target, distance) of the fixed camera: it frames the object and the hand."""
    start = np.array(task.object_spec.position, dtype=float)
    base = np.array(task.hand.base_position, dtype=float)
    target = (start + base) / 2
    reach = max(float(np.linalg.norm(base - start)), 0.05)
    return tuple(float(v) for v in target), 2.3 * reach


class FrameGrabber:
    """Collects camera images of the world being rendered (an on_frame callback)."""

    def __init__(self, task, view=None):
        target, distance = camera(task)
        self.yaw, self.pitch = view or (CAMERA_YAW, CAMERA_PITCH)
        self.target, self.distance = target, distance
        self.width, self.height = IMAGE_SIZE
        self.frames = []
        self.view = self.projection = None

    def colour(self, simulator):
        client = simulator.client
        for link in range(-1, client.getNumJoints(simulator.hand)):
            client.changeVisualShape(simulator.hand, link, rgbaColor=HAND_COLOUR)
        if simulator.object_body is not None:
            client.changeVisualShape(simulator.object_body, -1, rgbaColor=OBJECT_COLOUR)
        client.changeVisualShape(simulator.ground, -1, rgbaColor=GROUND_COLOUR)

    def __call__(self, step, simulator):
        client = simulator.client
        if self.view is None:
            self.view = client.computeViewMatrixFromYawPitchRoll(
                cameraTargetPosition=self.target, distance=self.distance, yaw=self.yaw,
                pitch=self.pitch, roll=0.0, upAxisIndex=2)
            self.projection = client.computeProjectionMatrixFOV(
                fov=45.0, aspect=self.width / self.height, nearVal=0.01, farVal=10.0)
        if step == 0:
            self.colour(simulator)
        _, _, pixels, _, _ = client.getCameraImage(
            self.width, self.height, self.view, self.projection,
            renderer=client.ER_TINY_RENDERER, shadow=1, lightDirection=(0.3, -1.0, 1.0))
        image = np.reshape(np.asarray(pixels, dtype=np.uint8), (self.height, self.width, 4))
        self.frames.append(image[:, :, :3].copy())


def frame_every(task):
    """Return the physics steps between two frames of the animation."""
    return max(1, int(round(1.0 / (FRAMES_PER_SECOND * task.time_step))))


def render_frames(task, design, world, view=None):
    """
    Return the RGB frames of one world's rollout of a RecordedDesign, from the camera.

    view: (yaw, pitch) of the camera in degrees, default (CAMERA_YAW, CAMERA_PITCH); a positive
    pitch looks up from below the ground, which the renderer leaves out, so a hand that
    reaches down onto an object is seen through the table.
    """
    physical = genome_spec(task).decode(design.x)
    grabber = FrameGrabber(task, view)
    if task.physics.engine != 'pybullet':
        return kinematic_frames(task, physical, world, grabber)
    with Simulator(rendering=True) as simulator:
        evaluation = evaluate_design(physical, task, worlds=[world], simulator=simulator,
                                     on_frame=grabber, frame_every=frame_every(task))
        if evaluation.collision or not grabber.frames:
            # nothing was simulated: show the start, where the hand touches something
            state = object_state(task, world)
            simulator.create_object(state, object_shape(simulator.client, state,
                                                        task.object_spec.shape))
            grabber(0, simulator)
    return grabber.frames


def kinematic_frames(task, physical, world, grabber):
    """
    Return the frames of a rollout simulated in another engine, drawn by PyBullet's camera.

    The other engine simulates; PyBullet only poses the same hand and object at its joint
    angles and object poses, frame by frame, and renders them.
    """
    poses = []

    def keep(step, simulator):
        poses.append((step, simulator.joint_angles(), simulator.object_pose()))

    with new_simulator(task.physics.engine) as other:
        evaluate_design(physical, task, worlds=[world], simulator=other, on_frame=keep,
                        frame_every=frame_every(task))
    state = object_state(task, world)
    with Simulator(rendering=True) as simulator:
        simulator.build(task, hand_model(physical.hand, task.hand))
        body = simulator.create_object(state, object_shape(simulator.client, state,
                                                           task.object_spec.shape))
        for step, angles, (position, orientation) in poses or [(0, None, None)]:
            if angles is not None:
                for joint, angle in enumerate(angles):
                    simulator.client.resetJointState(simulator.hand, joint, angle)
                simulator.client.resetBasePositionAndOrientation(body, position, orientation)
            grabber(step, simulator)
    return grabber.frames


def rollout_poses(task, design, world):
    """
    Return (HandModel, palm pose, frames) of one world's rollout of a RecordedDesign.

    frames: [(time s, link frames, object pose)] at the animation's frame rate, poses as
    (position, quaternion xyzw) in the world frame, link frames as core.sim.hand's table places
    them (at the joints). A design starting in collision is not simulated: one frame shows the
    start, the hand at its initial angles (core.experiments.motion.rollout_motion).
    """
    motion = rollout_motion(genome_spec(task).decode(design.x), task, world, FRAMES_PER_SECOND)
    return motion.model, motion.palm, list(zip(motion.times, motion.link_poses,
                                               motion.object_poses))


def render_gif(path, task, design, world, view=None):
    """Write the animated GIF of one world to path; return the number of frames."""
    import imageio.v3 as imageio
    frames = render_frames(task, design, world, view)
    try:
        with staged(path) as temporary:
            imageio.imwrite(temporary, np.stack(frames), extension='.gif',
                            duration=1000.0 / FRAMES_PER_SECOND, loop=0)
    except OSError as error:
        raise UserError(f'--gif {path}: cannot write: {error}') from None
    return len(frames)


def has_display():
    """Return whether a window can be opened (an X or Wayland display, or not Linux)."""
    if not sys.platform.startswith('linux'):
        return True
    return bool(os.environ.get('DISPLAY') or os.environ.get('WAYLAND_DISPLAY'))


def show_gui(task, design, world):
    """Play one world in the PyBullet window in real time, until the window is closed."""
    import pybullet
    from pybullet_utils.bullet_client import BulletClient
    simulator = Simulator(rendering=True)
    simulator.client.disconnect()
    try:
        simulator.client = BulletClient(connection_mode=pybullet.GUI)
    except pybullet.error as error:
        raise UserError(f'--gui: cannot open the PyBullet window: {error}') from None
    target, distance = camera(task)
    simulator.client.resetDebugVisualizerCamera(distance, CAMERA_YAW, CAMERA_PITCH, target)
    every = frame_every(task)

    def pace(step, _):
        time.sleep(every * task.time_step)

    try:
        evaluate_design(genome_spec(task).decode(design.x), task, worlds=[world],
                        simulator=simulator, on_frame=pace, frame_every=every)
        print('close the PyBullet window (or press Ctrl-C) to end')
        while simulator.client.isConnected():
            time.sleep(0.1)
    except pybullet.error:
        pass    # the window was closed
    finally:
        simulator.close()
