"""`hand-codesign check`: a task's genome, worlds, goals and budget, before any simulation."""

import json
import pathlib
import subprocess
import sys

from hand_codesign.cli import main
from hand_codesign.core import genome_spec, load_task, world_states
from hand_codesign.core.evaluate import evaluate
from hand_codesign.core.experiments.robustness import world_values
from hand_codesign.core.search.hierarchy import HierarchySearch
from hand_codesign.core.sim.objectives import goal_schedule
from hand_codesign.core.sim.worlds import object_state, QUANTITIES
import numpy as np
import pytest
import yaml

TASKS = pathlib.Path(__file__).resolve().parents[2] / 'config' / 'tasks'
PRESETS = sorted(TASKS.glob('*.yaml'))
COMMAND = pathlib.Path(sys.executable).with_name('hand-codesign')


def run_command(*arguments):
    """Run the installed console script; return the finished process."""
    return subprocess.run([str(COMMAND), *arguments], capture_output=True, text=True,
                          timeout=120)


def checked(capsys, *arguments):
    """Return the JSON of `hand-codesign check ... --json`, run in this process."""
    assert main(['check', *arguments, '--json']) == 0
    captured = capsys.readouterr()
    return json.loads(captured.out)


@pytest.mark.parametrize('path', PRESETS, ids=[path.stem for path in PRESETS])
def test_every_preset_checks(path, capsys):
    assert main(['check', str(path)]) == 0
    text = capsys.readouterr().out
    task = load_task(path)
    assert text.startswith(f'task {task.name} ({path}): valid')
    assert f'{task.num_world_states} training worlds of seed {task.seed}' in text
    summary = checked(capsys, str(path))
    assert len(summary['worlds']) == task.num_world_states
    assert summary['steps_per_evaluation'] == task.num_world_states * \
        summary['steps_per_rollout']


@pytest.mark.system
def test_json_round_trips_the_task():
    """The JSON of the real command holds what the core computes, float for float."""
    path = TASKS / 'task1.yaml'  # goals relative to the start, trajectories, a seed design
    process = run_command('check', str(path), '--json', '--world-states', '5')
    assert process.returncode == 0, process.stderr
    summary = json.loads(process.stdout)  # exactly one JSON object, nothing else
    task = load_task(path).replace(num_world_states=5)
    spec = genome_spec(task)
    assert [gene['name'] for gene in summary['genome']] == spec.names
    assert [gene['low'] for gene in summary['genome']] == spec.lower.tolist()
    assert [gene['high'] for gene in summary['genome']] == spec.upper.tolist()
    assert summary['hierarchy'] == []
    schedule = goal_schedule(task)
    samples = schedule.goal_samples()
    goals = sorted([(goal.time, 'position', goal.position) for goal in task.goals.position]
                   + [(goal.time, 'orientation', goal.orientation)
                      for goal in task.goals.orientation], key=lambda goal: goal[0])
    worlds = world_states(task)
    assert len(summary['worlds']) == len(worlds) == 5
    for world, entry in zip(worlds, summary['worlds']):
        assert [entry[name] for name in QUANTITIES] == list(world_values(world))
        state = object_state(task, world)
        assert entry['start'] == {'position': list(state.position),
                                  'orientation': list(state.orientation)}
        listed = [(goal['time'], kind, goal[kind]) for goal in entry['goals']
                  for kind in ('position', 'orientation') if goal[kind] is not None]
        assert len(listed) == len(goals) == 8
        for (time, kind, target), (listed_time, listed_kind, value) in zip(goals, listed):
            expected = schedule.world_goal(*((target, None) if kind == 'position'
                                             else (None, target)), state)
            assert (listed_time, listed_kind) == (time, kind)
            assert value == list(expected[0 if kind == 'position' else 1])
        assert len(entry['samples']) == len(samples) == 40
        for (name, time, target), sample in zip(samples, entry['samples']):
            kind = name.split('_')[0]
            expected = schedule.world_goal(*((target, None) if kind == 'position'
                                             else (None, target)), state)
            assert (sample['objective'], sample['time']) == (name, time)
            assert sample[kind] == list(expected[0 if kind == 'position' else 1])
    # the goals move with each world's start: the worlds' last goals differ
    last = [entry['goals'][-1]['orientation'] for entry in summary['worlds']]
    assert len({tuple(q) for q in last}) == 5
    assert summary['steps_per_rollout'] == 400  # 2 s of 0.005 s
    # two stages: stage 1 on the nominal world, stage 2 on the 5 worlds
    assert summary['budget']['stages'] == 2
    assert summary['budget']['physics_steps'] == 1000 * 250 * (1 + 5) * 400
    assert summary['budget']['structures'][0]['start'] == 'seed design'


def test_steps_per_evaluation_are_the_steps_evaluate_simulates(capsys):
    summary = checked(capsys, str(TASKS / 'task5.yaml'), '--world-states', '2')
    task = load_task(TASKS / 'task5.yaml').replace(num_world_states=2)
    evaluation = evaluate(genome_spec(task).initial_mean(), task)
    assert not evaluation.collision and evaluation.unstable_worlds == 0
    assert round(evaluation.simulated_time / task.time_step) == summary['steps_per_evaluation']
    assert summary['early_termination'] is None


def test_hierarchy_lists_its_structures_and_their_budget(capsys):
    summary = checked(capsys, str(TASKS / 'task4.yaml'))
    task = load_task(TASKS / 'task4.yaml')
    path = HierarchySearch(task).path
    grown = [[1, 1, 1], [1, 1, 2], [1, 1, 3], [1, 2, 2], [1, 2, 3]]
    assert summary['hierarchy'] == [[1], [2], [1, 1], [1, 2], [3], [1, 3], [2, 2], [2, 3]] + grown
    assert summary['hierarchy'][:len(path)] == [list(structure) for structure in path]
    assert summary['hierarchy_grown'] == {'count': 2, 'choices': grown}
    budget = summary['budget']
    assert [entry['genome_size'] for entry in budget['structures']] == [
        genome_spec(task.replace(structure=structure)).size
        for structure in path + [tuple(s) for s in grown]]
    # per structure twice 200 iterations x 150 candidates x 64 worlds, plus the check on 128
    # worlds, of 200 steps; 8 structures of the path and the 2 grown ones
    assert budget['physics_steps'] == 10 * (2 * 200 * 150 * 64 + 128) * 200
    assert any('hierarchy stops' in reason for reason in budget['may_end_early'])
    assert main(['check', str(TASKS / 'task4.yaml')]) == 0
    text = ' '.join(capsys.readouterr().out.split())  # unwrapped
    assert ('hierarchy: [1] -> [2] -> [1, 1] -> [1, 2] -> [3] -> [1, 3] -> [2, 2] -> [2, 3], '
            'then 2 of [1, 1, 1] [1, 1, 2] [1, 1, 3] [1, 2, 2] [1, 2, 3]') in text
    assert f'{budget["physics_steps"]:,} steps' in text
    assert '128 held-out world states, disjoint from the training worlds' in text
    held_out = world_states(task.replace(num_world_states=128, held_out=True))
    assert not set(held_out) & set(world_states(task))


def test_overrides_and_early_termination_are_shown(capsys):
    assert main(['check', str(TASKS / 'task3.yaml'), '--seed', '4', '--iterations', '3',
                 '--population', '6', '--world-states', '2']) == 0
    text = ' '.join(capsys.readouterr().out.split())  # unwrapped
    assert 'budget: mocma, 3 iterations x 6 candidates, 2 world states, seed 4' in text
    assert 'early termination can shorten a rollout' in text
    assert '3 x 6 x 800 per structure): 14,400 steps' in text
    summary = checked(capsys, str(TASKS / 'task3.yaml'), '--seed', '4', '--world-states', '2')
    seeded = load_task(TASKS / 'task3.yaml').replace(seed=4, num_world_states=2)
    assert summary['worlds'][1]['scale'] == world_states(seeded)[1].scale


def test_the_world_scoring_is_shown(capsys, tmp_path):
    assert main(['check', str(TASKS / 'task5.yaml')]) == 0
    text = ' '.join(capsys.readouterr().out.split())
    assert ('scoring: each objective is the mean over the worlds (eq. 5); every candidate '
            'meets the training worlds above') in text
    document = yaml.safe_load((TASKS / 'task5.yaml').read_text())
    document['worlds'] = {'aggregate': 'worst', 'fraction': 0.25, 'resample': 'generation',
                          'final_check': 3}
    path = tmp_path / 'robust.yaml'
    path.write_text(yaml.safe_dump(document))
    assert main(['check', str(path), '--iterations', '4', '--population', '6']) == 0
    text = ' '.join(capsys.readouterr().out.split())
    assert ('each objective is the mean over its worst 0.25 of the worlds (CVaR, '
            'worlds.aggregate: worst); each generation meets a fresh draw') in text
    assert 'of the best designs of the last 3 generations' in text
    summary = checked(capsys, str(path), '--iterations', '4', '--population', '6')
    assert summary['world_scoring'] == {'aggregate': 'worst', 'fraction': 0.25,
                                        'resample': 'generation', 'final_check': 3,
                                        'racing': None}
    # 4 x 6 evaluations, then the final check of 3 designs on the 8 worlds
    assert summary['budget']['evaluations'] == 4 * 6 + 3
    assert summary['budget']['rollouts'] == (4 * 6 + 3) * 8


def one_line_error(process, path):
    assert process.returncode == 2
    assert process.stdout == ''
    lines = process.stderr.strip().split('\n')
    assert len(lines) == 1, process.stderr
    assert str(path) in lines[0] and 'Traceback' not in process.stderr
    return lines[0]


@pytest.mark.system
def test_a_file_that_is_not_utf8_is_one_line(tmp_path):
    path = tmp_path / 'latin1.yaml'
    path.write_bytes((TASKS / 'task5.yaml').read_bytes() + '# d\xe9j\xe0 vu\n'.encode('latin-1'))
    line = one_line_error(run_command('check', str(path), '--json'), path)
    assert 'expected a task file in UTF-8 text, got byte 0xe9' in line
    bag = tmp_path / 'bag'
    assert 'UTF-8' in one_line_error(run_command('run', '--task', str(path), '--bag', str(bag),
                                                 '--domain-id', 'auto'),
                                     path)
    assert not bag.exists()


@pytest.mark.system
def test_a_missing_file_is_one_line(tmp_path):
    path = tmp_path / 'missing.yaml'
    assert 'cannot read the task file' in one_line_error(run_command('check', str(path)), path)


def test_broken_yaml_says_where_in_one_line(tmp_path, capsys):
    path = tmp_path / 'broken.yaml'
    path.write_text('name: broken\nseed: [1, 2\n')
    assert main(['check', str(path)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ''
    assert captured.err == (f"hand-codesign check: error: {path}: not valid YAML: expected ',' "
                            "or ']', but got '<stream end>' at line 3, column 1\n")


def test_a_hierarchy_that_cannot_reach_its_stop_is_refused(tmp_path, capsys):
    text = (TASKS / 'task4.yaml').read_text().replace('stop_structure: [2, 3]',
                                                      'stop_structure: [1, 1, 3]')
    text = text.replace('max_fingers: 3', 'max_fingers: 2')
    path = tmp_path / 'task4_bad_stop.yaml'
    path.write_text(text)
    assert load_task(path).hierarchy.stop_structure == (1, 1, 3)  # loads, but cannot run
    assert main(['check', str(path)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ''
    assert f'{path}: hierarchy: stop structure [1, 1, 3] is not on the bottom-up path' in \
        captured.err


def test_bad_override(capsys):
    assert main(['check', str(TASKS / 'task5.yaml'), '--population', '0']) == 2
    assert '--population: expected a positive number, got 0' in capsys.readouterr().err


def test_json_floats_are_exact(capsys):
    summary = checked(capsys, str(TASKS / 'task6.yaml'))
    task = load_task(TASKS / 'task6.yaml')
    state = object_state(task, world_states(task)[7])
    quaternion = summary['worlds'][7]['start']['orientation']
    assert quaternion == list(state.orientation)
    assert np.isclose(np.linalg.norm(quaternion), 1.0)


def test_racing_over_the_worlds_is_shown(tmp_path, capsys):
    document = yaml.safe_load((TASKS / 'task5.yaml').read_text())
    document['worlds'] = {'racing': {'rounds': 3, 'range': 0.05}}
    path = tmp_path / 'raced.yaml'
    path.write_text(yaml.safe_dump(document))
    assert main(['check', str(path), '--world-states', '64']) == 0
    text = ' '.join(capsys.readouterr().out.split())
    assert 'in 3 rounds (worlds [0, 21, 42, 64])' in text
    summary = checked(capsys, str(path), '--world-states', '64')
    assert summary['world_scoring']['racing'] == {'rounds': 3, 'range': 0.05, 'delta': 0.05,
                                                  'bounds': [0, 21, 42, 64]}
    assert any(reason.startswith('racing stops a candidate')
               for reason in summary['budget']['may_end_early'])
