"""Conversions between hand_codesign.core objects and hand_codesign_msgs messages."""

from hand_codesign_msgs.msg import Candidate
from hand_codesign_msgs.msg import Evaluation
from hand_codesign_msgs.msg import GenerationSummary
import numpy as np


def stamp_now(node):
    """Return the node's clock now as a builtin_interfaces/Time."""
    return node.get_clock().now().to_msg()


def float_list(values):
    """Return values as a flat list of Python floats, as float64[] fields take them."""
    return np.asarray(values, dtype=float).ravel().tolist()


def candidate_message(run_id, candidate, structure, genome_names, evaluator_id, attempt,
                      world_states=0):
    """
    Return the Candidate message sending an optimizer's candidate to an evaluator.

    world_states: 0 evaluates it on the run's worlds; more for a hierarchy structure's check.
    """
    return Candidate(
        run_id=run_id, generation=int(candidate.generation),
        candidate_id=int(candidate.candidate_id),
        evaluator_id=evaluator_id, attempt=int(attempt),
        structure=[int(joints) for joints in structure], genome=float_list(candidate.x),
        horizon=float(getattr(candidate, 'horizon', 0.0)),
        genome_names=list(genome_names), world_states=int(world_states),
        stage=int(getattr(candidate, 'stage', 0)),
        held_out_worlds=bool(getattr(candidate, 'held_out', False)))


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
        world_objectives=float_list(evaluation.world_objectives))


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
        final=bool(summary['final']), stop_reason=summary['stop_reason'])
