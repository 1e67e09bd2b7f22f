"""
The command line as a user meets it: help, names of quantities, the ROS domain.

Every verb's help shows the defaults and an example; one name per quantity across the
command line, task files and node parameters (old names still read with one line); one ROS
domain default for every verb that starts processes.
"""

import argparse
import json
import pathlib
import shlex
import subprocess
import sys

from hand_codesign import cli
from hand_codesign.ros.optimizer_node import PARAMETERS
import pytest
import yaml

ROOT = pathlib.Path(__file__).resolve().parents[2]
TASK = ROOT / 'config' / 'tasks' / 'task5.yaml'
COMMAND = pathlib.Path(sys.executable).parent / 'hand-codesign'


def verb_parsers():
    """Return {verb: its argparse parser}."""
    parser = cli.build_parser()
    verbs = next(action for action in parser._actions
                 if isinstance(action, argparse._SubParsersAction))
    return verbs.choices


def hand_codesign(*words):
    """Run the installed command from a plain shell's environment; return the process."""
    return subprocess.run([str(COMMAND), *map(str, words)], capture_output=True, text=True,
                          timeout=120, cwd=ROOT)


@pytest.mark.parametrize('verb', sorted(cli.VERBS))
def test_every_option_shows_its_default(verb):
    parser = verb_parsers()[verb]
    formatter = parser._get_formatter()
    silent = []
    for action in parser._actions:
        if (not action.option_strings or action.help == argparse.SUPPRESS
                or action.nargs == 0 or action.required):   # positional, hidden, a flag
            continue
        if 'default' not in formatter._expand_help(action):
            silent.append(action.option_strings[0])
    assert not silent, f'{verb}: options whose help shows no default: {silent}'


@pytest.mark.parametrize('verb', sorted(cli.VERBS))
def test_every_verb_shows_an_example_that_parses(verb):
    help_text = verb_parsers()[verb].format_help()
    example = help_text.split('example:\n', 1)[1].replace('\\\n', ' ')
    words = shlex.split(example)
    assert words[:2] == ['hand-codesign', verb]
    cli.build_parser().parse_args(words[1:])


def test_one_name_per_quantity_on_the_command_line_in_task_files_and_parameters():
    run = {action.dest for action in verb_parsers()['run']._actions}
    task = yaml.safe_load(TASK.read_text())
    assert {'population', 'world_states'} <= run
    assert {'population', 'world_states'} <= set(PARAMETERS)
    assert 'population' in task['optimizer'] and 'world_states' in task
    presets = sorted((ROOT / 'config').rglob('*.yaml'))
    assert not [path for path in presets if 'num_world_states' in path.read_text()]


@pytest.mark.system
def test_the_old_option_name_is_read_with_one_line():
    new = hand_codesign('check', TASK, '--population', '4', '--json')
    old = hand_codesign('check', TASK, '--popsize', '4', '--json')
    assert old.returncode == new.returncode == 0, old.stderr
    assert old.stdout == new.stdout
    assert old.stderr == ('hand-codesign: --popsize is an old name, read as --population: use '
                          '--population\n')
    assert '--popsize' not in hand_codesign('run', '--help').stdout


@pytest.mark.system
def test_the_old_task_key_is_read_with_one_line(tmp_path):
    text = TASK.read_text().replace('\nworld_states:', '\nnum_world_states:')
    old_file = tmp_path / 'old.yaml'
    old_file.write_text(text)
    old = hand_codesign('check', old_file, '--json')
    assert old.returncode == 0, old.stderr
    same = json.loads(hand_codesign('check', TASK, '--json').stdout)
    assert {**json.loads(old.stdout), 'source': ''} == {**same, 'source': ''}
    assert old.stderr == (f'hand-codesign: {old_file}: task key num_world_states is an old '
                          'name, read as world_states: use world_states\n')
    both = tmp_path / 'both.yaml'
    both.write_text(text + 'world_states: 4\n')
    twice = hand_codesign('check', both)
    assert twice.returncode == 2
    assert twice.stderr == (f'hand-codesign check: error: {both}: num_world_states and '
                            'world_states are one setting given twice: keep world_states\n')


def test_every_verb_that_starts_processes_has_the_same_domain_default():
    parsers = verb_parsers()
    helps = {verb: next(action.help for action in parsers[verb]._actions
                        if action.dest == 'domain_id') for verb in ('run', 'evaluate')}
    assert helps['run'] == helps['evaluate'] == cli.DOMAIN_HELP
    assert "the environment's" in cli.DOMAIN_HELP
    for verb in ('run', 'evaluate'):
        assert parsers[verb].parse_args(['bag'] if verb == 'evaluate' else []).domain_id is None
