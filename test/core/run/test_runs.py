"""The task a run uses: the task file's text plus the run's overrides, rebuilt alike everywhere."""

import pathlib
import re

from hand_codesign.core.run.runs import library_versions
from hand_codesign.core.run.runs import load_run_task
from hand_codesign.core.run.runs import run_task
from hand_codesign.core.task import load_task
from hand_codesign.core.task import TaskError
from hand_codesign.core.task.variant import Variant
import pytest

TASK = pathlib.Path(__file__).resolve().parents[3] / 'config' / 'tasks' / 'task5.yaml'


def test_overrides_replace_the_file_values_and_zero_or_none_keeps_them():
    plain = load_task(TASK)
    task = load_run_task(TASK, 11, 3, 8, 5)
    assert (task.seed, task.iterations, task.population, task.num_world_states) == (11, 3, 8, 5)
    kept = load_run_task(TASK)
    assert (kept.seed, kept.iterations, kept.population, kept.num_world_states) == (
        plain.seed, plain.iterations, plain.population, plain.num_world_states)
    assert kept.source_text == TASK.read_text()


def test_a_run_task_rebuilt_from_its_recorded_text_is_the_same_task():
    loaded = load_run_task(TASK, 11, 3, 8, 5)
    rebuilt = run_task(loaded.source_text, 'run x task', 11, 3, 8, 5)
    assert rebuilt.replace(source=loaded.source) == loaded
    assert run_task(loaded.source_text, 'run x task', 11, 0, 0, 0).population == (
        load_task(TASK).population)


def test_a_structure_override_gives_that_hand():
    rebuilt = run_task(TASK.read_text(), 'run x task', 1, 0, 0, 0, Variant(structure=(1, 2)))
    assert rebuilt.structure == (1, 2)


def test_a_broken_task_text_names_its_source():
    with pytest.raises(TaskError, match='run x task'):
        run_task('name: [unclosed', 'run x task', 1, 0, 0, 0)


def test_library_versions_name_every_result_relevant_package():
    versions = library_versions()
    assert [entry.split('==')[0] for entry in versions] == [
        'hand_codesign', 'pybullet', 'cma', 'deap', 'numpy']
    assert all(re.fullmatch(r'[\w-]+==[\w.+-]+', entry) for entry in versions)
