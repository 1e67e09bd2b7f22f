"""Conversions between hand_codesign.core objects and messages (ours, and standard ones)."""

from geometry_msgs.msg import Point
from geometry_msgs.msg import TransformStamped
from hand_codesign.core.contract import WORLD_FRAME
from hand_codesign_msgs.msg import Candidate
from hand_codesign_msgs.msg import Evaluation
from hand_codesign_msgs.msg import GenerationSummary
from hand_codesign_msgs.msg import TrialRequest
import numpy as np
from std_msgs.msg import ColorRGBA
from std_msgs.msg import String
from tf2_msgs.msg import TFMessage
from visualization_msgs.msg import Marker
from visualization_msgs.msg import MarkerArray

# core.sim.geometry's shape kinds -> Marker types
MARKER_TYPES = {'arrow': Marker.ARROW, 'box': Marker.CUBE, 'sphere': Marker.SPHERE,
                'cylinder': Marker.CYLINDER}


def stamp_now(node):
    """Return the node's clock now as a builtin_interfaces/Time."""
    return node.get_clock().now().to_msg()


def float_list(values):
    """Return values as a flat list of Python floats, as float64[] fields take them."""
    return np.asarray(values, dtype=float).ravel().tolist()


def candidate_message(run_id, candidate, genome_names, evaluator_id, attempt, design=None):
    """
    Return the Candidate message sending an optimizer's candidate to an evaluator.

    The candidate's Variant (core.task.variant) travels in the message's flat fields
    (structure, world_states, horizon, stage, held_out_worlds, world_draw), which
    core.run.evaluation_jobs.candidate_variant reads back into one Variant.
    design: its core.sim.physical.PhysicalDesign, for evaluators that do not decode genomes.
    """
    variant = candidate.variant
    message = Candidate(
        run_id=run_id, generation=int(candidate.generation),
        candidate_id=int(candidate.candidate_id),
        evaluator_id=evaluator_id, attempt=int(attempt),
        structure=[int(joints) for joints in variant.structure], genome=float_list(candidate.x),
        horizon=float(variant.horizon),
        genome_names=list(genome_names), world_states=int(variant.world_states),
        stage=int(variant.stage), held_out_worlds=bool(variant.held_out),
        world_draw=int(variant.world_draw))
    share = getattr(candidate, 'share', ())  # a racing round's (core.search.racing)
    if share:
        message.worlds_from, message.worlds_to = (int(index) for index in share)
    if design is not None:
        message.design_names = list(design.names)
        message.design_values = list(design.values)
        message.hand_urdf = design.urdf
        message.controller_kind = design.controller_kind
        message.controller_mode = design.controller_mode
        message.gravity_compensation = design.gravity_compensation
        message.controller_knot_times = list(design.knot_times)
        message.controller_values = list(design.controller_values)
        message.controller_kp = list(design.kp)
        message.controller_kd = list(design.kd)
    return message


def evaluation_message(candidate, evaluator_id, evaluation):
    """Return the Evaluation message answering a Candidate with a core Evaluation."""
    return Evaluation(
        run_id=candidate.run_id, generation=candidate.generation,
        candidate_id=candidate.candidate_id, attempt=candidate.attempt,
        evaluator_id=evaluator_id, status=Evaluation.STATUS_OK,
        objectives=float_list(evaluation.objectives),
        objective_names=list(evaluation.objective_names),
        fitness=float(evaluation.fitness), collision=bool(evaluation.collision),
        unstable_worlds=int(evaluation.unstable_worlds),
        simulated_time=float(evaluation.simulated_time),
        world_objectives=float_list(evaluation.world_objectives),
        outcome_names=list(evaluation.outcome_names), outcomes=float_list(evaluation.outcomes))


def rejection_message(candidate, evaluator_id, reason):
    """Return the Evaluation message refusing a candidate, with the reason."""
    return Evaluation(
        run_id=candidate.run_id, generation=candidate.generation,
        candidate_id=candidate.candidate_id, attempt=candidate.attempt,
        evaluator_id=evaluator_id, status=Evaluation.STATUS_REJECTED, reason=reason)


def summary_message(run_id, summary):
    """Return the GenerationSummary message of a core GenerationStats-like mapping."""
    front = np.asarray(summary['pareto_front'], dtype=float).reshape(-1, len(summary['names']))
    return GenerationSummary(
        run_id=run_id, generation=int(summary['generation']),
        structure=[int(joints) for joints in summary['structure']], check=summary['check'],
        horizon=float(summary.get('horizon', 0.0)),
        objective_names=list(summary['names']),
        best=float_list(summary['best']), median=float_list(summary['median']),
        worst=float_list(summary['worst']), pareto_size=int(front.shape[0]),
        pareto_front=float_list(front), best_candidate_id=int(summary['best_id']),
        best_objectives=float_list(summary['best_objectives']),
        best_fitness=float(summary['best_fitness']), best_genome=float_list(summary['best_x']),
        told_ids=summary['told_ids'], told_objectives=float_list(summary['told_objectives']),
        evaluations=int(summary['evaluations']), wall_time=float(summary['wall_time']),
        final=bool(summary['final']), stop_reason=summary['stop_reason'],
        rejected_evaluations=int(summary.get('rejected_evaluations', 0)),
        audit_evaluations=int(summary.get('audit_evaluations', 0)),
        audited_ids=[int(i) for i in summary.get('audited_ids', ())],
        quarantined=list(summary.get('quarantined', ())),
        reevaluations=int(summary.get('reevaluations', 0)),
        told_worlds=[int(worlds) for worlds in summary.get('told_worlds', ())])


def shape_marker(shape, number, stamp, frame_id=WORLD_FRAME):
    """Return the Marker of a core.sim.geometry Shape; `number` is its id within its group."""
    marker = Marker(ns=shape.group, id=int(number), type=MARKER_TYPES[shape.kind],
                    action=Marker.ADD, frame_locked=False)
    marker.header.frame_id = frame_id
    marker.header.stamp = stamp
    position, orientation = marker.pose.position, marker.pose.orientation
    position.x, position.y, position.z = (float(v) for v in shape.position)
    orientation.x, orientation.y, orientation.z, orientation.w = (
        float(v) for v in shape.orientation)
    marker.scale.x, marker.scale.y, marker.scale.z = (float(v) for v in shape.size)
    marker.color = ColorRGBA(**dict(zip('rgba', (float(v) for v in shape.colour))))
    marker.points = [Point(x=float(x), y=float(y), z=float(z)) for x, y, z in shape.points]
    return marker


def markers_message(shapes, stamp, frame_id=WORLD_FRAME):
    """
    Return the MarkerArray drawing core.sim.geometry Shapes, numbered within each group.

    It starts with a DELETEALL marker, so that a viewer drops the shapes of the previous
    array (a design of another structure has another number of segments).
    """
    clear = Marker(action=Marker.DELETEALL)
    clear.header.frame_id = frame_id
    clear.header.stamp = stamp
    counts = {}
    markers = [clear]
    for shape in shapes:
        number = counts[shape.group] = counts.get(shape.group, -1) + 1
        markers.append(shape_marker(shape, number, stamp, frame_id))
    return MarkerArray(markers=markers)


def trial_request(candidate, evaluator_id, trial_id, spec):
    """Return the TrialRequest of one trial (a core.rig.trials.TrialSpec) of a candidate."""
    return TrialRequest(
        run_id=candidate.run_id, candidate_id=candidate.candidate_id,
        attempt=candidate.attempt, evaluator_id=evaluator_id, trial_id=int(trial_id),
        world=spec.world, worlds=spec.worlds, object_shape=spec.shape,
        object_size=list(spec.size), object_scale=float(spec.scale),
        object_position=list(spec.position), object_orientation=list(spec.orientation),
        object_mass=float(spec.mass), object_friction=float(spec.friction),
        duration=float(spec.duration))


def robot_description_message(urdf):
    """Return the std_msgs/String of a robot_description topic: the URDF text."""
    return String(data=urdf)


def tf_message(transforms, stamp):
    """
    Return the tf2_msgs/TFMessage of (parent frame, child frame, (translation, quaternion)).

    Each becomes a TransformStamped: the child frame's pose in its parent's, as tf2 and
    robot_state_publisher publish them (core.sim.geometry.joint_transforms).
    """
    message = TFMessage()
    for parent, child, (translation, rotation) in transforms:
        transform = TransformStamped(child_frame_id=child)
        transform.header.frame_id = parent
        transform.header.stamp = stamp
        moved, turned = transform.transform.translation, transform.transform.rotation
        moved.x, moved.y, moved.z = (float(v) for v in translation)
        turned.x, turned.y, turned.z, turned.w = (float(v) for v in rotation)
        message.transforms.append(transform)
    return message
