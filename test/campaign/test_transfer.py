"""`hand-codesign transfer`: the committed tables of designs measured in both engines."""

import contextlib
import io
import pathlib
import shutil

from hand_codesign.cli import main
import pytest

RESULTS = pathlib.Path(__file__).resolve().parents[2] / 'docs' / 'results'


def transfer(*arguments):
    """Run `hand-codesign transfer ...` in this process; return (code, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(['transfer', *map(str, arguments)])
    return code, out.getvalue(), err.getvalue()


@pytest.mark.parametrize('name', ['task5-transfer', 'task6-transfer', 'task5-transfer-paper',
                                  'task6-transfer-paper'])
def test_the_committed_tables_come_back_from_their_folders(name, tmp_path):
    committed = (RESULTS / f'{name}.md').read_text()
    title, note = committed.split('\n\n')[0][2:], committed.split('\n\n')[1]
    shutil.copytree(RESULTS / name, tmp_path / name)
    code, printed, error = transfer(tmp_path / name, '--title', title, '--note', note)
    assert code == 0, error
    assert (tmp_path / f'{name}.md').read_text() == committed
    assert (tmp_path / f'{name}.csv').read_text() == (RESULTS / f'{name}.csv').read_text()
    assert printed.startswith(f'wrote {tmp_path / name}.csv')


def test_a_folder_that_is_not_there_or_holds_one_engine_gets_one_line(tmp_path):
    code, _, error = transfer(tmp_path / 'nothing', '--title', 'x')
    assert code == 2 and error.count('\n') == 1 and 'not a folder' in error
    (tmp_path / 'one').mkdir()
    (tmp_path / 'one' / 'run-in-mujoco.json').write_text('{}')
    code, _, error = transfer(tmp_path / 'one', '--title', 'x')
    assert code == 2 and error.count('\n') == 1 and 'expected both' in error
