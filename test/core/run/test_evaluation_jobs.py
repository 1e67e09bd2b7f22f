"""What an evaluator takes and evaluates, from real Candidate and RunInfo messages, without ROS."""

import dataclasses
import pathlib

from hand_codesign.core.evaluate import evaluate
from hand_codesign.core.run.evaluation_jobs import CandidateRejected
from hand_codesign.core.run.evaluation_jobs import evaluation_job
from hand_codesign.core.run.evaluation_jobs import EvaluatorInbox
from hand_codesign.core.run.runs import engine_version, load_run_task
from hand_codesign.core.sim.worlds import world_states
from hand_codesign.core.task.genome import genome_spec
from hand_codesign_msgs.msg import Candidate
from hand_codesign_msgs.msg import RunInfo
import numpy as np
import pytest

TASK = pathlib.Path(__file__).resolve().parents[3] / 'config' / 'tasks' / 'task5.yaml'


@pytest.fixture(scope='module')
def run():
    task = load_run_task(TASK, 7, 3, 6, 3)
    return RunInfo(run_id='run-1', task_name=task.name, task_yaml=task.source_text,
                   seed=task.seed, iterations=3, population=6, world_states=3), task


def candidate(candidate_id=0, genome=None, structure=(2, 2), **fields):
    genome = [0.5] * 24 if genome is None else genome
    return Candidate(**{'run_id': 'run-1', 'candidate_id': candidate_id, 'genome': genome,
                        'structure': list(structure), **fields})


def same_task(built, loaded):
    """Return whether a task built from a RunInfo is the loaded one (its source aside)."""
    return dataclasses.replace(built, source=loaded.source) == loaded


class Clock:
    now = 0.0

    def __call__(self):
        return self.now


def test_an_evaluation_is_the_core_evaluation_of_the_run_task(run):
    run_info, task = run
    genome = np.linspace(0.1, 0.9, 24)
    job = evaluation_job(run_info, candidate(genome=genome.tolist()))
    assert same_task(job.task, task) and job.worlds is None
    assert np.array_equal(evaluate(job.genome, job.task, job.worlds).objectives,
                          evaluate(genome, task).objectives)


def test_a_check_candidate_is_evaluated_on_the_worlds_it_names(run):
    run_info, task = run
    job = evaluation_job(run_info, candidate(world_states=5))
    assert job.task.num_world_states == 5 and job.task.seed == task.seed


def test_a_resampled_candidate_is_evaluated_on_the_draw_it_names(run):
    run_info, task = run
    job = evaluation_job(run_info, candidate(world_draw=4))
    assert job.task.world_draw == 4 and job.task.num_world_states == 3
    assert world_states(job.task) == world_states(task.replace(world_draw=4))
    assert world_states(job.task) != world_states(task)
    assert evaluation_job(run_info, candidate()).task.world_draw == 0


def test_another_structure_gets_its_own_genome(run):
    run_info, task = run
    size = genome_spec(task.replace(structure=(1,))).size
    job = evaluation_job(run_info, candidate(genome=[0.5] * size, structure=(1,)))
    assert job.task.structure == (1,)


@pytest.mark.parametrize('fields, reason', [
    ({'genome': [0.5]}, 'genome has 1 values, structure (2, 2) of task task5 needs 24'),
    ({'genome': [float('nan')] * 24}, 'genome contains NaN or infinite values'),
    ({'structure': (0, 7)}, 'unusable structure or task'),
])
def test_malformed_candidates_are_rejected_with_the_reason(run, fields, reason):
    with pytest.raises(CandidateRejected, match=reason.replace('(', r'\(').replace(')', r'\)')):
        evaluation_job(run[0], candidate(**fields))


def test_the_inbox_takes_its_own_candidates_once(run):
    inbox = EvaluatorInbox('me')
    inbox.run_announced(run[0])
    assert inbox.candidate_arrived(candidate(0, evaluator_id='someone-else')) == []
    mine = candidate(1, evaluator_id='me')
    assert inbox.candidate_arrived(mine) == [mine]
    assert inbox.candidate_arrived(candidate(1, evaluator_id='me')) == []   # seen
    again = candidate(1, attempt=1)                                       # sent again
    assert inbox.candidate_arrived(again) == [again]
    assert same_task(inbox.job(again).task, run[1])
    # every message given counts, its own or not: the evaluator takes messages while it grows
    assert inbox.heard == 5


def test_an_inbox_for_one_run_ignores_the_others(run):
    inbox = EvaluatorInbox('me', wanted_run='run-2')
    assert inbox.run_announced(run[0]) == []
    assert inbox.candidate_arrived(candidate(0)) == []
    assert inbox.orphans() == []


def test_a_candidate_waits_for_its_run_info_then_is_rejected_without_it(run):
    clock = Clock()
    inbox = EvaluatorInbox('me', run_info_wait=10.0, clock=clock)
    early = candidate(0)
    assert inbox.candidate_arrived(early) == []
    assert inbox.run_announced(run[0]) == [early]
    lost = candidate(5, run_id='run-without-info')
    assert inbox.candidate_arrived(lost) == []
    clock.now = 9.0
    assert inbox.orphans() == []
    clock.now = 10.5
    assert inbox.orphans() == [lost]
    with pytest.raises(CandidateRejected, match='no RunInfo received for run "run-without'):
        inbox.job(lost)


def test_the_run_info_names_the_engine_and_an_evaluator_with_another_version_refuses(run):
    run_info, task = run
    mujoco_run = RunInfo(run_id='run-1', task_yaml=task.source_text, seed=task.seed,
                         iterations=3, population=6, world_states=3, engine='mujoco',
                         engine_version=engine_version('mujoco'))
    job = evaluation_job(mujoco_run, candidate())
    assert job.task.physics.engine == 'mujoco'
    assert evaluation_job(run_info, candidate()).task.physics.engine == 'pybullet'
    other = RunInfo(run_id='run-1', task_yaml=task.source_text, engine='mujoco',
                    engine_version='mujoco==3.3.0')
    with pytest.raises(CandidateRejected) as refused:
        evaluation_job(other, candidate())
    assert str(refused.value) == (f'run run-1 simulates with mujoco==3.3.0; this evaluator has '
                                  f'{engine_version("mujoco")}: results would differ')
    with pytest.raises(CandidateRejected, match="physics engine 'ode'"):
        evaluation_job(RunInfo(run_id='run-1', task_yaml=task.source_text, engine='ode'),
                       candidate())
