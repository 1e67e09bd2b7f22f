"""tools/campaign_rates.py on folders that are not whole campaigns, and on bad flags."""

import pathlib
import shutil
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
TOOL = ROOT / 'tools' / 'campaign_rates.py'


def run_tool(*arguments):
    return subprocess.run([sys.executable, str(TOOL), *map(str, arguments)],
                          capture_output=True, text=True, timeout=300)


def test_a_folder_that_is_no_campaign_gets_one_line_naming_it(tmp_path):
    completed = run_tool(tmp_path, 'levers-task5')
    assert completed.returncode != 0 and completed.stdout == ''
    lines = completed.stderr.strip().splitlines()
    assert len(lines) == 1 and str(tmp_path) in lines[0] and 'runs/ and tasks/' in lines[0]


def test_an_unknown_budget_names_the_experiments_budgets(tmp_path):
    completed = run_tool(tmp_path, 'levers-task5', '--budget', 'huge')
    assert completed.returncode == 2 and 'Traceback' not in completed.stderr
    assert 'no budget "huge"; expected one of smoke, reduced, paper' in completed.stderr


def test_a_campaign_of_some_configurations_lists_only_those(tmp_path):
    # the committed levers-task5 table ran 13 of the experiment's configurations (--only)
    shutil.copytree(ROOT / 'docs' / 'results' / 'levers-task5-reduced' / 'tasks',
                    tmp_path / 'tasks')
    (tmp_path / 'runs').mkdir()
    completed = run_tool(tmp_path, 'levers-task5', '--budget', 'reduced')
    assert completed.returncode == 0, completed.stderr
    listed = [line.split()[0] for line in completed.stdout.splitlines()
              if line.endswith('no finished run')]
    assert sorted(listed) == sorted(path.stem for path in (tmp_path / 'tasks').glob('*.yaml'))
    assert len(listed) == 13 and 'cma-palm-beside' not in listed
