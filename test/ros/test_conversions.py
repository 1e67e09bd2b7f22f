"""Core objects to messages: what travels is what the core computed, through serialization."""

import dataclasses
import pathlib

from hand_codesign.core.evaluate import evaluate
from hand_codesign.core.run.runs import load_run_task
from hand_codesign.core.run.summary import generation_summary
from hand_codesign.core.search.optimizers import Candidate as CoreCandidate
from hand_codesign.core.search.optimizers import OptimizerResult
from hand_codesign.core.sim.physical import candidate_design
from hand_codesign.core.sim.physical import design_from_physical
from hand_codesign.core.task.genome import genome_spec
from hand_codesign.core.task.variant import Variant
from hand_codesign.ros.conversions import candidate_message
from hand_codesign.ros.conversions import evaluation_message
from hand_codesign.ros.conversions import rejection_message
from hand_codesign.ros.conversions import summary_message
from hand_codesign_msgs.msg import Candidate
from hand_codesign_msgs.msg import Evaluation
from hand_codesign_msgs.msg import GenerationSummary
import numpy as np
from rclpy.serialization import deserialize_message
from rclpy.serialization import serialize_message

TASK = pathlib.Path(__file__).resolve().parents[2] / 'config' / 'tasks' / 'task5.yaml'


def through_the_wire(message):
    return deserialize_message(serialize_message(message), type(message))


def core_candidate():
    return CoreCandidate(candidate_id=12, generation=2, x=np.linspace(0.0, 1.0, 24),
                         variant=Variant(structure=(2, 2)))


def test_a_candidate_message_carries_the_design_that_rebuilds_it():
    task = load_run_task(TASK)
    candidate = core_candidate()
    physical = candidate_design(task, candidate.x)
    message = through_the_wire(candidate_message(
        'run-1', candidate, [f'g{i}' for i in range(24)], '', 0, physical))
    assert message.hand_urdf == physical.urdf
    assert (message.controller_kind, message.controller_mode) == ('torque', 'constant')
    assert list(message.controller_knot_times) == list(physical.knot_times)
    rebuilt = design_from_physical(message.structure, message.design_names,
                                   message.design_values, message.controller_kind,
                                   message.controller_values, message.controller_kp,
                                   message.controller_kd)
    assert rebuilt == genome_spec(task).decode(candidate.x)


def test_a_candidate_message_carries_genome_structure_and_worlds():
    checked = dataclasses.replace(core_candidate(), variant=Variant(structure=(2, 2),
                                                                    world_states=64))
    message = through_the_wire(candidate_message(
        'run-1', checked, [f'g{i}' for i in range(24)], 'evaluator-1', 3))
    assert (message.run_id, message.candidate_id, message.generation) == ('run-1', 12, 2)
    assert (message.evaluator_id, message.attempt, message.world_states) == (
        'evaluator-1', 3, 64)
    assert list(message.structure) == [2, 2]
    assert np.array_equal(np.asarray(message.genome), core_candidate().x)
    assert list(message.genome_names)[:2] == ['g0', 'g1']
    plain = candidate_message('run-1', core_candidate(), [], '', 0)
    assert plain.world_states == 0 and plain.world_draw == 0
    drawn = dataclasses.replace(core_candidate(), variant=Variant(structure=(2, 2), world_draw=5))
    assert through_the_wire(candidate_message('run-1', drawn, [], '', 0)).world_draw == 5


def test_an_evaluation_message_holds_the_core_evaluation_bit_for_bit():
    task = load_run_task(TASK, 7, 1, 4, 2)
    evaluation = evaluate(np.full(24, 0.5), task)
    request = Candidate(run_id='run-1', generation=0, candidate_id=3, attempt=1)
    message = through_the_wire(evaluation_message(request, 'evaluator-1', evaluation))
    assert message.status == Evaluation.STATUS_OK and message.reason == ''
    assert (message.candidate_id, message.attempt) == (3, 1)
    assert np.asarray(message.objectives).tolist() == evaluation.objectives.tolist()
    assert message.fitness == evaluation.fitness
    assert np.asarray(message.world_objectives).reshape(2, -1).tolist() == (
        evaluation.world_objectives.tolist())
    assert list(message.objective_names) == list(evaluation.objective_names)


def test_a_rejection_says_why_and_has_no_objectives():
    request = Candidate(run_id='run-1', generation=0, candidate_id=3, attempt=2)
    message = through_the_wire(rejection_message(request, 'evaluator-1', 'genome has NaN'))
    assert message.status == Evaluation.STATUS_REJECTED and message.reason == 'genome has NaN'
    assert (message.candidate_id, message.attempt, len(message.objectives)) == (3, 2, 0)


def test_a_summary_message_holds_the_summary():
    names = ('position_1', 'orientation_1')
    front = np.array([[0.5, 0.25], [0.25, 0.5]])
    result = OptimizerResult(candidate_id=7, generation=1, x=np.array([0.25, 0.5]),
                             objectives=np.array([0.5, 0.25]), fitness=0.525, evaluations=8,
                             iterations=2, pareto_objectives=front)
    summary = generation_summary(1, (2, 2), names, [6, 7], [[1.0, 0.5], [0.5, 0.25]], result,
                                 8, 2.5)
    message = through_the_wire(summary_message('run-1', summary))
    assert isinstance(message, GenerationSummary)
    assert (message.generation, message.pareto_size, message.best_candidate_id) == (1, 2, 7)
    assert np.asarray(message.pareto_front).reshape(-1, 2).tolist() == front.tolist()
    assert list(message.told_ids) == [6, 7]
    assert np.asarray(message.told_objectives).tolist() == [1.0, 0.5, 0.5, 0.25]
    assert np.asarray(message.best).tolist() == [0.5, 0.25]
    assert message.best_fitness == 0.525 and message.wall_time == 2.5
    assert not message.final and not message.check
