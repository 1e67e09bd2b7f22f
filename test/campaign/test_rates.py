"""`hand-codesign reproduce EXPERIMENT --rates` on folders that are not whole campaigns."""

import contextlib
import io
import pathlib
import shutil
import types

from hand_codesign.cli import main

ROOT = pathlib.Path(__file__).resolve().parents[2]


def rates(folder, experiment, *arguments):
    """Run `hand-codesign reproduce EXPERIMENT --out FOLDER --rates ...` in this process."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(['reproduce', experiment, '--out', str(folder), '--rates', *arguments])
    return types.SimpleNamespace(returncode=code, stdout=out.getvalue(), stderr=err.getvalue())


def test_a_folder_that_is_no_campaign_gets_one_line_naming_it(tmp_path):
    completed = rates(tmp_path, 'levers-task5')
    assert completed.returncode == 2 and completed.stdout == ''
    lines = completed.stderr.strip().splitlines()
    assert len(lines) == 1 and str(tmp_path) in lines[0] and 'runs/ and tasks/' in lines[0]


def test_an_unknown_budget_names_the_experiments_budgets(tmp_path):
    completed = rates(tmp_path, 'levers-task5', 'huge')
    assert completed.returncode == 2 and 'Traceback' not in completed.stderr
    assert 'no budget "huge"; expected one of smoke, reduced, paper' in completed.stderr


def test_a_campaign_of_some_configurations_lists_only_those(tmp_path):
    # the committed levers-task5 table ran 13 of the experiment's configurations (--only)
    shutil.copytree(ROOT / 'docs' / 'results' / 'levers-task5-reduced' / 'tasks',
                    tmp_path / 'tasks')
    (tmp_path / 'runs').mkdir()
    completed = rates(tmp_path, 'levers-task5', 'reduced')
    assert completed.returncode == 0, completed.stderr
    listed = [line.split()[0] for line in completed.stdout.splitlines()
              if line.endswith('no finished run')]
    assert sorted(listed) == sorted(path.stem for path in (tmp_path / 'tasks').glob('*.yaml'))
    assert len(listed) == 13 and 'cma-palm-beside' not in listed
