"""
The task file's schema, declared once, and the presets `reproduce` runs.

Its table in docs/TASK.md, a new key as one field, and each pinned preset against its
namesake in config/tasks/.
"""

import dataclasses
import pathlib
import re
import warnings

from hand_codesign.core.task import load_task
from hand_codesign.core.task.document import keys_table, with_keys
from hand_codesign.core.task.parts import TaskError, WorldsSpec
from hand_codesign.core.task.schema import entries, key, rows, settings
from hand_codesign.core.task.spec import Task
from hand_codesign.core.task.values import ValueReader
from hand_codesign.deprecation import OldName
import pytest
import yaml

ROOT = pathlib.Path(__file__).resolve().parents[3]
PINNED = sorted((ROOT / 'config' / 'reproduce').glob('*.yaml'))
DECLARED = re.compile(r'(Same as|Differs from) (config/tasks/[\w.]+\.yaml) in '
                      r'(every key|[\w.]+(?:, [\w.]+)*)[:,.]?\s*(.*)$')


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


def test_a_renamed_key_is_read_under_its_old_name_with_one_line():
    # the old name is declared on the key: the reader takes it, says so once, and the docs
    # name it; a recorded task (warn_old_names False) reads silently
    @dataclasses.dataclass(frozen=True)
    class Worlds(WorldsSpec):
        repeats: int = key('times each world is evaluated', 'integer', default=1,
                           old='repetitions')

    with pytest.warns(OldName) as said:
        read = ValueReader('new.yaml', warn_old_names=True).section(
            Worlds, {'repetitions': 3}, 'worlds')
    assert read['repeats'] == 3
    assert [str(line.message) for line in said] == [
        'new.yaml: task key worlds.repetitions is an old name, read as worlds.repeats: use '
        'worlds.repeats']
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        assert ValueReader('bag').section(Worlds, {'repetitions': 3}, 'worlds')['repeats'] == 3
    with pytest.raises(TaskError, match='worlds.repetitions and worlds.repeats are one '
                                        'setting given twice: keep repeats'):
        ValueReader('new.yaml').section(Worlds, {'repetitions': 3, 'repeats': 2}, 'worlds')
    assert any(line.startswith('| `world_states` |') and 'old name `num_world_states`' in line
               for line in keys_table())


def declared(path):
    """Return (namesake, keys it differs in or None for none, why) of a pinned preset."""
    header = []
    for line in path.read_text(encoding='utf-8').splitlines():
        if not line.startswith('#'):
            break
        header.append(line.lstrip('# ').strip())
    text = ' '.join(header)
    found = [DECLARED.search(sentence) for sentence in re.split(r'(?<=\.) (?=[A-Z])', text)]
    match = next((item for item in found if item), None)
    assert match, f'{path.name}: its header says "Same as config/tasks/X.yaml in every key" or ' \
                  '"Differs from config/tasks/X.yaml in KEY, ...: why"'
    kind, namesake, keys, why = match.groups()
    named = None if keys == 'every key' else {name.strip() for name in keys.split(',')}
    return ROOT / namesake, named, (why or '').strip()


def differences(first, second):
    """Return the keys (section.key, or a top-level key) whose values differ."""
    def flat(document):
        found = {}
        for name, value in document.items():
            if isinstance(value, dict) and name not in ('description',):
                found.update({f'{name}.{inner}': item for inner, item in value.items()})
            else:
                found[name] = value
        return found
    first_doc, second_doc = (yaml.safe_load(path.read_text()) for path in (first, second))
    # a section only one of them has is one difference: the section
    missing = set(first_doc) ^ set(second_doc)
    one, two = (flat({name: value for name, value in document.items() if name not in missing})
                for document in (first_doc, second_doc))
    return missing | {name for name in set(one) | set(two) if one.get(name) != two.get(name)}


@pytest.mark.parametrize('path', PINNED, ids=[path.name for path in PINNED])
def test_a_pinned_preset_differs_from_its_namesake_only_where_its_header_says_why(path):
    namesake, named, why = declared(path)
    assert namesake.exists(), namesake
    assert differences(namesake, path) == (named or set()), path.name
    if named:
        assert why, f'{path.name}: say why it differs'
