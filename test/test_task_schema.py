"""The task file's schema, declared once: its table in docs/TASK.md, a new key as one field."""

import dataclasses
import pathlib

from hand_codesign.core.task import load_task
from hand_codesign.core.task.document import with_keys
from hand_codesign.core.task.parts import TaskError, WorldsSpec
from hand_codesign.core.task.schema import entries, key, rows, settings
from hand_codesign.core.task.spec import Task
from hand_codesign.core.task.values import ValueReader
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]


def test_docs_task_md_is_what_the_schema_writes():
    # after adding or changing a key: python tools/task_doc.py
    text = (ROOT / 'docs' / 'TASK.md').read_text(encoding='utf-8')
    assert with_keys(text) == text


def test_every_key_of_the_table_has_a_meaning_and_every_preset_key_a_row():
    paths = {row.path for row in rows(Task)}
    assert all(row.spec.meaning for row in rows(Task))
    for preset in sorted((ROOT / 'config' / 'tasks').glob('*.yaml')):
        for dotted in settings(load_task(preset)):
            assert dotted in paths, (preset.name, dotted)


def test_a_new_key_is_one_field():
    # a key declared on a section's dataclass is read, checked and defaulted with no code more
    @dataclasses.dataclass(frozen=True)
    class Worlds(WorldsSpec):
        repeats: int = key('times each world is evaluated', 'integer', default=1)

    reader = ValueReader('new.yaml')
    read = Worlds(**reader.section(Worlds, {'repeats': 3}, 'worlds'))
    assert read.repeats == 3 and read.aggregate == 'mean'
    assert Worlds(**reader.section(Worlds, {}, 'worlds')).repeats == 1
    with pytest.raises(TaskError, match=r'new.yaml: worlds.repeats: expected a positive '
                                        r'integer, got 0'):
        reader.section(Worlds, {'repeats': 0}, 'worlds')
    assert 'repeats' in [entry.field for entry in entries(Worlds)]
