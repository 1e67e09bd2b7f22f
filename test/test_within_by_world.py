"""tools/within_by_world.py, called as RESULTS calls it, on a committed campaign's measures."""

import os
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
TOOL = ROOT / 'tools' / 'within_by_world.py'


def run_tool(*arguments):
    return subprocess.run([sys.executable, str(TOOL), *arguments], capture_output=True,
                          text=True, timeout=300, cwd=ROOT)


def test_a_folder_without_measures_gets_one_line_naming_it(tmp_path):
    result = run_tool(str(tmp_path), 'levers-task6', '--seeds', '3')
    assert result.returncode != 0
    assert result.stdout == ''
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and str(tmp_path) in lines[0] and 'measures' in lines[0]


def test_the_committed_rerun_gives_the_bands_results_cites():
    result = run_tool('docs/results/levers-task6-reduced-rerun', 'levers-task6', '--seeds', '3',
                      '--bands', '0.5', '0.75', '1', '1.5', '2')
    assert result.returncode == 0, result.stderr
    row = next(line for line in result.stdout.splitlines()
               if line.startswith('cma-diagonal-fingers-60mm '))
    assert row.split('|')[0].split()[1:] == ['16', '%', 'of', '491']
    assert [cell.split()[0] for cell in row.split('|')[1:]] == ['40', '56', '43']


def test_piped_into_head_it_ends_quietly():
    reading_end, writing_end = os.pipe()
    os.close(reading_end)  # a reader that has already taken what it wanted
    try:
        result = subprocess.run([sys.executable, str(TOOL), 'docs/results/levers-task5-reduced',
                                 'levers-task5', '--seeds', '5'], stdout=writing_end,
                                stderr=subprocess.PIPE, text=True, timeout=300, cwd=ROOT)
    finally:
        os.close(writing_end)
    assert result.returncode == 141 and result.stderr == ''
