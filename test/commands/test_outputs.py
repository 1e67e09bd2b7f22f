"""Outputs appear whole or not at all (hand_codesign.outputs): a failure blocks no retry."""

from hand_codesign.outputs import staged
import pytest


class Broken(Exception):
    pass


def test_a_file_appears_only_once_written(tmp_path):
    path = tmp_path / 'out' / 'rollout.mcap'
    with staged(path) as temporary:
        temporary.write_text('data')
        assert not path.exists() and temporary.suffix == '.mcap'
    assert path.read_text() == 'data'
    assert list(path.parent.iterdir()) == [path]


def test_a_failure_leaves_nothing(tmp_path):
    path = tmp_path / 'report'
    with pytest.raises(Broken):
        with staged(path) as temporary:
            temporary.mkdir()
            (temporary / 'evaluations.csv').write_text('half')
            raise Broken()
    assert list(tmp_path.iterdir()) == []
    with staged(path) as temporary:   # the retry
        temporary.mkdir()
        (temporary / 'evaluations.csv').write_text('whole')
    assert (path / 'evaluations.csv').read_text() == 'whole'


def test_an_existing_folder_gets_the_new_files_and_keeps_others(tmp_path):
    path = tmp_path / 'report'
    (path / 'structure_2').mkdir(parents=True)
    (path / 'notes.txt').write_text('mine')
    (path / 'report.md').write_text('old')
    with staged(path) as temporary:
        (temporary / 'structure_2').mkdir(parents=True)
        (temporary / 'structure_2' / 'worlds.csv').write_text('new')
        (temporary / 'report.md').write_text('new')
    assert (path / 'notes.txt').read_text() == 'mine'
    assert (path / 'report.md').read_text() == 'new'
    assert (path / 'structure_2' / 'worlds.csv').read_text() == 'new'
    assert sorted(p.name for p in tmp_path.iterdir()) == ['report']
