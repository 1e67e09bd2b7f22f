"""`hand-codesign reproduce EXPERIMENT --bands`, as RESULTS calls it, on committed measures."""

import os
import pathlib
import subprocess
import sys

import pytest

pytestmark = pytest.mark.system

ROOT = pathlib.Path(__file__).resolve().parents[2]
COMMAND = [sys.executable, '-m', 'hand_codesign.cli', 'reproduce']


def run_bands(out, experiment, *arguments):
    return subprocess.run([*COMMAND, experiment, '--out', str(out), *arguments],
                          capture_output=True, text=True, timeout=300, cwd=ROOT)


def test_a_folder_without_measures_gets_one_line_naming_it(tmp_path):
    result = run_bands(tmp_path, 'levers-task6', '--seeds', '3', '--bands', '0.5', '2')
    assert result.returncode == 2
    assert result.stdout == ''
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and str(tmp_path) in lines[0] and 'measures' in lines[0]


def test_the_committed_rerun_gives_the_bands_results_cites():
    result = run_bands('docs/results/levers-task6-reduced-rerun', 'levers-task6', '--seeds', '3',
                       '--bands', '0.5', '0.75', '1', '1.5', '2')
    assert result.returncode == 0, result.stderr
    row = next(line for line in result.stdout.splitlines()
               if line.startswith('cma-diagonal-fingers-60mm '))
    assert row.split('|')[0].split()[1:] == ['16', '%', 'of', '491']
    assert [cell.split()[0] for cell in row.split('|')[1:]] == ['40', '56', '43']


def test_bands_that_do_not_ascend_or_an_unknown_quantity_get_one_line(tmp_path):
    for arguments in (['--bands', '2', '1'], ['--bands', '1'],
                      ['--bands', '1', '2', '--quantity', 'colour']):
        result = run_bands(tmp_path, 'levers-task6', *arguments)
        assert result.returncode == 2 and 'Traceback' not in result.stderr
        assert len(result.stderr.strip().splitlines()) == 1, result.stderr


def test_piped_into_head_it_ends_quietly():
    reading_end, writing_end = os.pipe()
    os.close(reading_end)  # a reader that has already taken what it wanted
    try:
        result = subprocess.run([*COMMAND, 'levers-task5', '--out',
                                 'docs/results/levers-task5-reduced', '--seeds', '5', '--bands',
                                 '0.5', '1', '2'], stdout=writing_end,
                                stderr=subprocess.PIPE, text=True, timeout=300, cwd=ROOT)
    finally:
        os.close(writing_end)
    assert result.returncode == 141 and result.stderr == ''
