"""
`hand-codesign reproduce`: experiments, pinned presets, measures on unseen worlds, campaigns.

The campaign test runs a tiny experiment of two real runs (real processes, real PyBullet),
interrupts it in the middle of its second run, continues it, and recomputes the table's
numbers from the bags.
"""

import csv
import dataclasses
import json
import math
import os
import pathlib
import re
import signal
import subprocess
import sys
import textwrap
import time

from hand_codesign import cli
from hand_codesign.analysis import records, unseen
from hand_codesign.campaign import experiment as definition
from hand_codesign.campaign import experiments
from hand_codesign.campaign.figures import convergence_panels
from hand_codesign.commands import reproduce
from hand_codesign.core.evaluate import evaluate
from hand_codesign.core.experiments.measures import (measure_worlds, shares_in_bands, summarize,
                                                     Tolerance, unseen_world_states)
from hand_codesign.core.outcomes import fingers, LIMIT_TOLERANCE, resting_on_limit_touching
from hand_codesign.core.rotations import axis_angle_quaternion, compose
from hand_codesign.core.sim.worlds import world_states
from hand_codesign.core.task import load_task, parse_task
from hand_codesign.core.task.genome import genome_spec
import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
TASK5 = ROOT / 'config' / 'reproduce' / 'task5.yaml'
TASK5_ALONG_X = ROOT / 'config' / 'reproduce' / 'task5_along_x.yaml'


@pytest.mark.system
def test_list_names_every_experiment_first_on_its_line(capsys):
    assert cli.main(['reproduce', '--list']) == 0
    lines = capsys.readouterr().out.splitlines()
    names = [line.split()[0] for line in lines]
    assert names == experiments.experiment_names()
    for name in ('task5-joint-limits', 'task6-rotation', 'task4-hierarchy', 'task1-seeded',
                 'all'):
        assert name in names


@pytest.mark.system
def test_unknown_experiment_is_one_line(capsys):
    assert cli.main(['reproduce', 'task9']) == 2
    error = capsys.readouterr().err.strip()
    assert error.count('\n') == 0 and 'task9' in error and 'task5-joint-limits' in error


@pytest.mark.parametrize('name', list(experiments.EXPERIMENTS))
def test_configurations_pin_their_algorithm_and_preset(name):
    experiment = experiments.EXPERIMENTS[name]
    keys = [configuration.key for configuration in experiment.configurations]
    assert len(set(keys)) == len(keys)
    assert set(experiment.budgets) == {'smoke', 'reduced', 'paper'}
    for configuration in experiment.configurations:
        preset = definition.pinned_dir() / configuration.preset
        text = definition.configuration_task_text(configuration, preset.read_text())
        task = parse_task(text, source=str(preset))
        assert task.algorithm == configuration.algorithm
        expected = ('CMA-ES', 'MO-CMA-ES') if not experiment.beyond_paper else (
            definition.ALGORITHM_NAMES.values())
        assert configuration.algorithm_name in expected
        if not configuration.options:
            assert text.count('#') == preset.read_text().count('#')  # comments kept


def test_all_runs_the_papers_experiments_and_levers_set_their_options():
    names = [experiment.name for experiment in experiments.paper_experiments()]
    assert names == ['task5-joint-limits', 'task6-rotation', 'task4-hierarchy', 'task1-seeded',
                     'task2-seeded']
    levers = experiments.EXPERIMENTS['levers-task5']
    assert levers.beyond_paper
    by_key = {configuration.key: configuration for configuration in levers.configurations}
    preset = definition.pinned_dir() / 'task5.yaml'
    worst = parse_task(definition.configuration_task_text(by_key['cma-worst25'],
                                                          preset.read_text()))
    resampled = parse_task(definition.configuration_task_text(by_key['cma-resample'],
                                                              preset.read_text()))
    both = parse_task(definition.configuration_task_text(by_key['cma-worst25-resample'],
                                                         preset.read_text()))
    paper = parse_task(preset.read_text())
    assert (worst.worlds.aggregate, worst.worlds.fraction) == ('worst', 0.25)
    assert resampled.worlds.resample == 'generation'
    assert (both.worlds.aggregate, both.worlds.fraction, both.worlds.resample) == (
        'worst', 0.25, 'generation')
    for task in (worst, resampled, both):  # nothing else changed
        assert task.replace(worlds=paper.worlds, source_text=paper.source_text) == paper
    along_x = parse_task(definition.configuration_task_text(
        by_key['cma-along-x'], (definition.pinned_dir() / 'task5_along_x.yaml').read_text()))
    assert [goal.axes for goal in along_x.goals.position] == [('x',)]
    assert along_x.replace(goals=paper.goals, source_text=paper.source_text) == paper
    assert levers.tolerances() == (Tolerance('plane', 0.005), Tolerance('x', 0.005),
                                   Tolerance('y', 0.005))
    # Task 6's hand turned 45 degrees about the vertical, fingers directly opposite, the box's
    # 90-degree symmetry: nothing else changed
    task6 = parse_task((definition.pinned_dir() / 'task6.yaml').read_text())
    diagonal, = [c for c in experiments.EXPERIMENTS['levers-task6'].configurations
                 if c.key == 'cma-diagonal']
    turned = parse_task(definition.configuration_task_text(
        diagonal, (definition.pinned_dir() / diagonal.preset).read_text()))
    _, palm = compose(((0, 0, 0), axis_angle_quaternion((0, 0, 1), math.pi / 4)),
                      ((0, 0, 0), task6.hand.base_orientation))
    np.testing.assert_allclose(turned.hand.base_orientation, palm, atol=1e-7)
    assert turned.morphology.finger_position_z.values == (0.0,)
    assert turned.goals.orientation_symmetry.order == 4
    assert turned.replace(
        hand=dataclasses.replace(turned.hand, base_orientation=task6.hand.base_orientation),
        morphology=dataclasses.replace(turned.morphology,
                                       finger_position_z=task6.morphology.finger_position_z),
        goals=dataclasses.replace(turned.goals,
                                  orientation_symmetry=task6.goals.orientation_symmetry),
        source_text=task6.source_text) == task6
    for name in ('levers-task5', 'levers-task6'):  # quality diversity, its archive's defaults
        mae, = [c for c in experiments.EXPERIMENTS[name].configurations if c.key == 'cma-mae']
        text = (definition.pinned_dir() / mae.preset).read_text()
        task = parse_task(definition.configuration_task_text(mae, text))
        assert (task.algorithm, task.archive, mae.algorithm_name) == ('cma-mae', None, 'CMA-MAE')
        assert task.replace(algorithm='cma', source_text='') == parse_task(text).replace(
            source_text='')
    # CMA-MAE over the joint-limit span and the outcome limit_rest, on each preset's lever
    for name, key, preset in (('levers-task5', 'cma-mae-limit-rest-along-x', 'task5_along_x'),
                              ('levers-task6', 'cma-mae-limit-rest-diagonal', 'task6_diagonal')):
        mae, = [c for c in experiments.EXPERIMENTS[name].configurations if c.key == key]
        text = (definition.pinned_dir() / f'{preset}.yaml').read_text()
        assert mae.preset == f'{preset}.yaml'
        task = parse_task(definition.configuration_task_text(mae, text))
        assert task.algorithm == 'cma-mae'
        assert task.archive.descriptors == ('joint_range', 'limit_rest')
        assert task.replace(algorithm='cma', archive=None, source_text='') == parse_task(
            text).replace(source_text='')
    # the probe of the diagonal hand on the smaller half of the boxes: trained and measured
    # there alone, nothing else changed
    probe, = [c for c in experiments.EXPERIMENTS['levers-task6'].configurations
              if c.key == 'cma-diagonal-smaller-boxes']
    text = (definition.pinned_dir() / probe.preset).read_text()
    task = parse_task(definition.configuration_task_text(probe, text))
    scales = [world.scale for world in unseen_world_states(task, 300)]
    assert 0.5 <= min(scales) < 0.55 and 0.95 < max(scales) <= 1.0
    assert task.replace(randomization=parse_task(text).randomization,
                        source_text='') == parse_task(text).replace(source_text='')
    # the fingers placed closer to the box: nothing else changed
    for key, placement in (('cma-diagonal-fingers-60mm', 0.06),
                           ('cma-diagonal-fingers-45mm', 0.045)):
        closer, = [c for c in experiments.EXPERIMENTS['levers-task6'].configurations
                   if c.key == key]
        task = parse_task(definition.configuration_task_text(closer, text))
        assert task.morphology.finger_position_x.values == (-placement, placement)
        pinned = parse_task(text)
        assert task.replace(morphology=pinned.morphology, source_text='') == pinned.replace(
            source_text='')
    reduced = levers.budget('reduced')
    assert (reduced.iterations, reduced.population, reduced.seeds) == (40, 40, 5)
    assert definition.training_worlds(by_key['cma'], reduced) == 16
    assert definition.training_worlds(by_key['cma'], levers.budget('paper')) == 64


def test_task6_paper_hand_levers_change_one_thing_each_or_two_together():
    # the levers on Task 6's paper hand (the palm beside the box), chosen on tuning seeds
    text = (definition.pinned_dir() / 'task6_palm_beside.yaml').read_text()
    pinned = parse_task(text).replace(source_text='')
    by_key = {c.key: c for c in experiments.EXPERIMENTS['levers-task6'].configurations
              if c.key.startswith('cma-palm-beside-') and 'hardest' not in c.key
              and not c.key.endswith('-placed')}
    assert len(by_key) == 7 and all(c.preset == 'task6_palm_beside.yaml'
                                    for c in by_key.values())

    def lever(key):
        return parse_task(definition.configuration_task_text(by_key[key], text)).replace(
            source_text='')

    worst, both = lever('cma-palm-beside-worst25'), lever('cma-palm-beside-worst25-resample')
    assert (worst.worlds.aggregate, worst.worlds.fraction) == ('worst', 0.25)
    assert lever('cma-palm-beside-resample').worlds.resample == 'generation'
    assert (both.worlds.aggregate, both.worlds.resample) == ('worst', 'generation')
    for key in ('cma-palm-beside-worst25', 'cma-palm-beside-resample',
                'cma-palm-beside-worst25-resample'):
        assert lever(key).replace(worlds=pinned.worlds) == pinned
    wider = lever('cma-palm-beside-sigma-0.2')
    assert wider.initial_sigma == 0.2 and wider.replace(
        initial_sigma=pinned.initial_sigma) == pinned
    np.testing.assert_allclose(pinned.hand.base_position, (-0.075, 0.0, 0.015))
    for key, distance in (('cma-palm-beside-palm-85mm', 0.085),
                          ('cma-palm-beside-palm-70mm', 0.07)):
        moved = lever(key)
        np.testing.assert_allclose(moved.hand.base_position, (-distance, 0.0, 0.015))
        assert moved.replace(hand=pinned.hand) == pinned
    # the two levers chosen together: the closer palm and the worst quarter, nothing else
    together = lever('cma-palm-beside-palm-70mm-worst25')
    assert together.replace(hand=pinned.hand, worlds=pinned.worlds) == pinned
    assert together.hand == lever('cma-palm-beside-palm-70mm').hand
    assert together.worlds == worst.worlds


@pytest.mark.parametrize('experiment, key, unplaced, preset, genes', [
    ('levers-task5', 'cma-placed', None, 'task5.yaml', 4),
    ('levers-task5', 'cma-goal-y-placed', None, 'task5_goal_y.yaml', 4),
    ('levers-task5', 'cma-goal-y-placed-sigma-0.3', None, 'task5_goal_y.yaml', 4),
    ('levers-task6', 'cma-palm-beside-placed', None, 'task6_palm_beside.yaml', 3),
    ('task4-structures', 'mocma-1-3-placed-mujoco', 'mocma-1-3-mujoco', 'task4_structure.yaml',
     4),
    ('task4-structures', 'mocma-2-2-placed-mujoco', 'mocma-2-2-mujoco', 'task4_structure.yaml',
     4)])
def test_placed_levers_search_the_palm_around_the_presets_own_placement(
        experiment, key, unplaced, preset, genes):
    # the palm's place and turn searched, nothing else changed: the preset's own placement
    # (or that of the configuration without placement) lies inside the bounds, and each range
    # wider than a point is one more gene
    text = (definition.pinned_dir() / preset).read_text()
    configurations = {c.key: c for c in experiments.EXPERIMENTS[experiment].configurations}

    def configured(configuration_key):
        configuration = configurations[configuration_key]
        assert configuration.preset == preset
        return parse_task(definition.configuration_task_text(configuration, text)).replace(
            source_text='')

    pinned = configured(unplaced) if unplaced else parse_task(text).replace(source_text='')
    placed = configured(key)
    assert placed.hand.placement_searched and not pinned.hand.placement_searched
    for value, bounds in zip(pinned.hand.base_position, placed.hand.base_position_bounds):
        assert bounds.lower <= value <= bounds.upper
    assert placed.hand.base_yaw_bounds.lower < 0.0 < placed.hand.base_yaw_bounds.upper
    assert placed.replace(hand=pinned.hand, initial_sigma=pinned.initial_sigma) == pinned
    assert placed.initial_sigma == (0.3 if key.endswith('sigma-0.3') else pinned.initial_sigma)
    assert genome_spec(placed).size == genome_spec(pinned).size + genes


def test_the_goal_along_y_moves_the_goal_alone():
    # a user's goal in a new direction: Task 5 with its goal 1 cm along y instead of x
    paper = parse_task((definition.pinned_dir() / 'task5.yaml').read_text())
    along_y = parse_task((definition.pinned_dir() / 'task5_goal_y.yaml').read_text())
    np.testing.assert_allclose(paper.goals.position[0].position, (0.01, 0.0, 0.02))
    np.testing.assert_allclose(along_y.goals.position[0].position, (0.0, 0.01, 0.02))
    assert along_y.replace(goals=paper.goals, source_text='') == paper.replace(source_text='')


def test_task6_hardest_boxes_probes_narrow_the_worlds_to_their_corner():
    # the probes train and measure Task 6's paper hand on the boxes hardest to turn alone
    text = (definition.pinned_dir() / 'task6_palm_beside.yaml').read_text()
    pinned = parse_task(text).replace(source_text='')
    by_key = {c.key: c for c in experiments.EXPERIMENTS['levers-task6'].configurations}

    def probe(key):
        return parse_task(definition.configuration_task_text(by_key[key], text)).replace(
            source_text='')

    corner = probe('cma-palm-beside-hardest-boxes')
    stronger = probe('cma-palm-beside-hardest-boxes-torque-0.05')
    for task in (corner, stronger):
        randomization = task.randomization
        assert (randomization.scale.lower, randomization.scale.upper) == (1.75, 2.0)
        assert (randomization.mass.lower, randomization.mass.upper) == (1.35, 1.5)
        assert (randomization.friction.lower, randomization.friction.upper) == (0.025, 0.05)
        assert randomization.position == pinned.randomization.position
    assert corner.replace(randomization=pinned.randomization) == pinned
    bound = stronger.policy.torque.values[0]
    assert (bound.lower, bound.upper) == (-0.05, 0.05)
    assert stronger.policy.torque != pinned.policy.torque
    assert stronger.replace(randomization=pinned.randomization, policy=pinned.policy,
                            torque_penalty=pinned.torque_penalty) == pinned


def test_unseen_worlds_are_disjoint_from_training_and_nested():
    task = load_task(TASK5).replace(seed=3)
    unseen = unseen_world_states(task, 200)
    training = world_states(task, 200)
    assert not set(unseen) & set(training)
    assert unseen[:50] == unseen_world_states(task, 50)
    assert unseen != unseen_world_states(task.replace(seed=4), 200)
    assert unseen == unseen_world_states(task, 200)


def test_measures_come_from_the_evaluated_rollout():
    task = load_task(TASK5).replace(seed=1)
    x = np.random.default_rng(5).random(len(genome_spec(task).names))
    worlds = unseen_world_states(task, 6)
    measured = measure_worlds(x, task, worlds)
    evaluation = evaluate(x, task, worlds=worlds)
    assert np.array_equal(measured.errors['position'], evaluation.final_errors[:, 0])
    assert np.array_equal(measured.errors['orientation'], evaluation.final_errors[:, 1])
    # the plane error leaves out the height: at most the 3-D distance
    assert np.all(measured.errors['plane'] <= measured.errors['position'] + 1e-12)


def test_the_error_along_x_is_the_distance_of_a_goal_that_measures_x_alone():
    # task5_along_x.yaml's position goal measures x alone: eq. (3)'s distance is |x offset|
    task = load_task(TASK5_ALONG_X).replace(seed=2)
    assert task.goals.position[-1].axes == ('x',)
    x = np.random.default_rng(7).random(len(genome_spec(task).names))
    measured = measure_worlds(x, task, unseen_world_states(task, 6))
    for errors in (measured.errors, measured.initial_errors):
        np.testing.assert_allclose(errors['x'], errors['position'], rtol=0, atol=1e-12)
        np.testing.assert_allclose(np.hypot(errors['x'], errors['y']), errors['plane'],
                                   rtol=0, atol=1e-12)
    assert np.any(measured.errors['y'] > 1e-4)  # the worlds' offsets along y are kept
    assert Tolerance('x', 0.005).describe() == 'error along x < 5 mm'


class FinalState:
    """Records at each frame the joints, their limits and the links touching the object."""

    def __init__(self):
        self.last = None

    def __call__(self, step, simulator):
        client, hand = simulator.client, simulator.hand
        links = simulator.model.links
        angles = [state[0] for state in client.getJointStates(hand, list(range(len(links))))]
        touching = {point[3] for point in client.getContactPoints(hand, simulator.object_body)
                    if point[8] <= 0.001}
        self.last = (angles, [(link.lower_limit, link.upper_limit) for link in links],
                     touching, fingers(links), resting_on_limit_touching(simulator))


def test_resting_on_a_limit_while_touching_matches_the_final_state():
    from hand_codesign.core.evaluate import _TaskContext, evaluate_design
    task = load_task(TASK5).replace(seed=1)
    spec = genome_spec(task)
    generator = np.random.default_rng(0)
    world = unseen_world_states(task, 1)
    seen = set()
    for _ in range(12):
        x = generator.random(len(spec.names))
        flag = bool(measure_worlds(x, task, world).limit_contacts[0])
        final = FinalState()
        design = _TaskContext.of(task).genome_spec().decode(x)
        evaluation = evaluate_design(design, task, world, on_frame=final, frame_every=300)
        if evaluation.collision:
            assert not flag
            continue
        angles, limits, touching, groups, _ = final.last
        expected = any(
            touching.intersection(finger)
            and any(angles[j] <= limits[j][0] + LIMIT_TOLERANCE
                    or angles[j] >= limits[j][1] - LIMIT_TOLERANCE for j in finger)
            for finger in groups)
        assert flag == expected
        seen.add(flag)
    assert seen == {True, False}, 'the sample should hold designs of both kinds'


# 20 generations: long enough that the run is still going when the test, having seen its
# first generation in the bag (flushed every second), interrupts it
TINY = """
    import sys
    from hand_codesign.cli import main
    from hand_codesign.campaign.experiment import Budget, Configuration, Experiment
    from hand_codesign.campaign.experiments import EXPERIMENTS
    from hand_codesign.core.experiments.measures import Tolerance
    EXPERIMENTS['tiny'] = Experiment(
        'tiny', 'two small Task 5 runs',
        (Configuration('torque-cma-2w', 'task5.yaml', 'cma', 2, 'torque'),
         Configuration('torque-mocma-16w', 'task5.yaml', 'mocma', 16, 'torque')),
        Tolerance('plane', 0.005), {'smoke': Budget('smoke', 20, 4, 12, 1)},
        also=(Tolerance('x', 0.005),))
    sys.exit(main(['reproduce', 'tiny', '--budget', 'smoke', '--evaluators', '1',
                   '--out', sys.argv[1]] + sys.argv[2:]))
"""


def start_tiny(script, out, *options, background=False):
    # a session of its own, as a campaign started from a shell: SIGINT reaches it alone, and
    # nothing pytest's process did to its own signal state is inherited; in the background
    # (`nohup ... &` from a script) it and its children ignore SIGINT
    return subprocess.Popen([sys.executable, str(script), str(out), *options], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env=dict(os.environ), start_new_session=True,
                            preexec_fn=ignore_interrupts if background else unblock_interrupts)


def unblock_interrupts():
    signal.pthread_sigmask(signal.SIG_UNBLOCK, [signal.SIGINT])
    signal.signal(signal.SIGINT, signal.default_int_handler)


def ignore_interrupts():
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def wait_for_a_generation(bag, process, timeout=180.0):
    """Wait until the bag of a run in progress holds a GenerationSummary."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and process.poll() is None:
        if bag.exists() and any(bag.glob('*.mcap')):
            try:
                if len(records.open_run(bag, warn=False).generation_summaries):
                    return
            except Exception:  # noqa: B902: a bag being written may not open yet
                pass
        time.sleep(0.2)
    raise AssertionError(f'no generation in {bag} in time')


def test_time_left_is_fitted_to_runs_simulated_whole_in_this_session():
    # a continued campaign first measures or resumes the runs it left: seconds for a whole
    # run's budget, which made the 17 runs left of a campaign look like 41 s
    progress = reproduce.Progress(total=3)
    progress.pending = [1000, 1000, 1000]
    progress.done(1000, 2.0, whole=False)
    assert progress.seconds_left() is None
    progress.done(1000, 300.0)
    assert progress.seconds_left() == pytest.approx(300.0)
    # runs of nearly the same cost (a final check adds a little) and noisy times: no line
    # through two close points, whose slope would swing to hours or to nothing
    progress.pending += [1001, 1002]
    progress.done(1001, 320.0)
    assert progress.seconds_left() == pytest.approx((300.0 + 320.0) / 2001 * (1000 + 1002))


@pytest.mark.system
def test_interrupted_campaign_keeps_finished_runs_resumes_and_tables_recompute(tmp_path):
    # started in the background and stopped with SIGTERM (as `kill` does): the run it forwards
    # the stop to closes its bag although it ignores SIGINT, well before the 120 s after which
    # the campaign would kill it and leave its nodes running
    script = tmp_path / 'tiny.py'
    script.write_text(textwrap.dedent(TINY))
    out = tmp_path / 'campaign'
    runs = out / 'runs'
    first = start_tiny(script, out, background=True)
    try:
        wait_for_a_generation(runs / 'torque-mocma-16w-seed1', first)
        first.send_signal(signal.SIGTERM)
        output, _ = first.communicate(timeout=100)
    finally:
        if first.poll() is None:
            first.kill()
    assert first.returncode == 130, output
    assert 'run 2 of 2' in output and 'run the same command again' in output
    # its runs are quiet but for a progress line every few minutes: here the first alone
    assert 'generation 1/20 [2x2]' in output and 'generation 2/20' not in output
    finished = runs / 'torque-cma-2w-seed1' / 'result.json'
    stamp = finished.stat().st_mtime_ns
    assert not (runs / 'torque-mocma-16w-seed1' / 'result.json').exists()

    second = start_tiny(script, out)
    output, _ = second.communicate(timeout=300)
    assert second.returncode == 0, output
    assert 'run 1 of 2: torque-cma-2w-seed1 (finished and measured: kept)' in output
    assert 'run 2 of 2: torque-mocma-16w-seed1 (resuming from its bag)' in output
    assert finished.stat().st_mtime_ns == stamp
    assert not (runs / 'torque-cma-2w-seed1.resume1').exists()
    resumed = runs / 'torque-mocma-16w-seed1.resume1'
    assert records.open_run(resumed, warn=False).run_info.resumed_from

    with open(out / 'tiny.csv', newline='', encoding='utf-8') as stream:
        table = {row['configuration']: row for row in csv.DictReader(stream)}
    assert set(table) == {'torque-cma-2w', 'torque-mocma-16w'}
    assert table['torque-mocma-16w']['algorithm'] == 'MO-CMA-ES'
    assert table['torque-cma-2w']['algorithm'] == 'CMA-ES'
    tolerance = Tolerance('plane', 0.005)
    for key, bag in (('torque-cma-2w', finished.parent), ('torque-mocma-16w', resumed)):
        task, x, _ = records.final_design(bag)
        measured = measure_worlds(x, task, unseen_world_states(task, 12))
        summary = summarize(measured, tolerance)
        row = table[key]
        assert float(row['within_x']) == summarize(measured, Tolerance('x', 0.005)).within
        assert float(row['within']) == summary.within
        assert float(row['within_by_seed']) == summary.within  # one seed: its own share
        assert float(row['median']) == summary.median
        assert float(row['p90']) == summary.p90
        assert int(row['joint_limits_found']) == int(summary.joint_limits_found)
        assert row['seeds'] == '1' and row['unseen_worlds'] == '12'
    assert (out / 'tiny.md').read_text().count('| torque-') == 2
    assert 'within (error along x < 5 mm)' in (out / 'tiny.md').read_text()
    assert (out / 'tiny.png').stat().st_size > 0

    # measures cached before an error kind the tables need existed are measured again; --only
    # takes one configuration, and the tables keep every configuration measured
    cached = out / 'measures' / 'torque-cma-2w-seed1.json'
    values = json.loads(cached.read_text())
    del values['worlds']['errors']['x']
    cached.write_text(json.dumps(values))
    third = start_tiny(script, out, '--only', 'torque-cma-2w')
    output, _ = third.communicate(timeout=300)
    assert third.returncode == 0, output
    assert 'run 1 of 1: torque-cma-2w-seed1 (finished: measuring)' in output
    assert 'torque-mocma-16w' not in output.split('reproduce: tiny (')[0]
    assert 'x' in json.loads(cached.read_text())['worlds']['errors']
    assert (out / 'tiny.md').read_text().count('| torque-') == 2

    # the convergence figure has a panel for each configuration with runs, none for the rest
    configurations = tuple(
        definition.Configuration(key, 'task5.yaml', algorithm, worlds, 'torque')
        for key, algorithm, worlds in (('torque-cma-2w', 'cma', 2),
                                       ('never-run', 'cma', 2),
                                       ('torque-mocma-16w', 'mocma', 16)))
    tiny = definition.Experiment('tiny', '', configurations, tolerance, {})
    panels = convergence_panels(out, tiny, seeds=(1,))
    assert [label for label, _ in panels] == ['torque-cma-2w (CMA-ES)',
                                              'torque-mocma-16w (MO-CMA-ES)']
    assert all(len(told) == len(best) > 0 for _, curves in panels for _, (told, best) in curves)


@pytest.mark.system
def test_only_names_configurations_of_the_experiment(capsys):
    assert cli.main(['reproduce', 'levers-task6', '--only', 'cma-diagonal', 'nope']) == 2
    error = capsys.readouterr().err.strip()
    assert error.count('\n') == 0 and 'nope' in error and 'cma-diagonal-gravity' in error


def test_analyze_reports_only_the_errors_of_the_tasks_goals():
    # Task 6's final position is irrelevant: the box's way from its start is no error there
    rotation = unseen.unseen_tolerances(load_task(ROOT / 'config' / 'tasks' / 'task6.yaml'))
    assert [tolerance.kind for tolerance in rotation] == ['orientation']
    alignment = unseen.unseen_tolerances(load_task(ROOT / 'config' / 'reproduce' /
                                                   'task5.yaml'))
    kinds = [tolerance.kind for tolerance in alignment]
    # and both together, a pose error (Task 4's success: the box turned and kept in place)
    assert kinds == ['plane', 'position', 'x', 'y', 'orientation', 'pose']


def test_bands_are_scored_on_the_error_the_tasks_goal_measures():
    def scored(folder, name):
        return unseen.scored_tolerance(load_task(ROOT / 'config' / folder / name)).kind
    assert scored('tasks', 'task5.yaml') == 'plane'  # the paper's task: the plane of the table
    assert scored('tasks', 'task5_along_x.yaml') == 'x'  # the named variant: x alone
    assert scored('reproduce', 'task5.yaml') == 'plane'
    assert scored('tasks', 'task6.yaml') == 'orientation'


def test_shares_in_bands_take_every_world_once():
    values = np.array([0.0, 0.25, 0.5, 0.75, 1.0])
    within = np.array([True, False, True, True, False])
    bands = shares_in_bands(values, within, [0.0, 0.5, 1.0])
    assert bands == [(0.0, 0.5, 2, 0.5), (0.5, 1.0, 3, 2 / 3)]
    assert shares_in_bands(values, within, [2.0, 3.0]) == [(2.0, 3.0, 0, None)]


@pytest.mark.system
def test_analyze_reports_the_same_measures_for_one_run(real_run, tmp_path, capsys):
    out = tmp_path / 'report'
    assert cli.main(['analyze', str(real_run.bag), '--out', str(out), '--unseen', '20']) == 0
    printed = capsys.readouterr().out
    assert 'On 20 unseen worlds' in printed and 'joint limits found' in printed
    values = json.loads((out / 'unseen.json').read_text())
    task, x, _ = records.final_design(real_run.bag)
    measured = measure_worlds(x, task, unseen_world_states(task, 20))
    plane = summarize(measured, Tolerance('plane', 0.005))
    assert values['summaries'][0]['within'] == plane.within
    assert values['summaries'][0]['median'] == plane.median
    assert values['summaries'][0]['joint_limits_found'] == plane.joint_limits_found
    assert (out / 'unseen.md').read_text().count('| ') >= 4
    along = {summary['tolerance']['kind']: summary['within'] for summary in values['summaries']}
    for axis in 'xy':  # where the box ends along each axis of the plane
        assert along[axis] == summarize(measured, Tolerance(axis, 0.005)).within
    assert 'error along y < 5 mm' in (out / 'unseen.md').read_text()
    # where in each randomized range the design fails: bands of the error the task scores
    bands = values['bands']
    scored = Tolerance(**bands['tolerance'])
    assert scored == unseen.scored_tolerance(task)
    within = measured.errors[scored.kind] < scored.limit
    scales = np.array([world.scale for world in unseen_world_states(task, 20)])
    lower, upper = task.randomization.scale.lower, task.randomization.scale.upper
    edges = np.linspace(lower, upper, unseen.BANDS + 1)
    for (low, high, count, share), band_low, band_high in zip(
            bands['quantities']['scale'], edges, edges[1:]):
        inside = (scales >= band_low) & (scales <= band_high)
        assert (low, high, count) == (band_low, band_high, int(inside.sum()))
        assert share == (np.mean(within[inside]) if count else None)
    assert sum(count for _, _, count, _ in bands['quantities']['scale']) == 20
    assert '| scale |' in printed


def test_every_preset_and_table_named_in_results_exists_and_checks():
    # docs/RESULTS.md's figures and its experiment pages' (docs/results/*/README.md) stand on
    # presets and committed tables: each one they name must be there, and each preset must
    # load as a task (what `hand-codesign check` validates)
    pages = [ROOT / 'docs' / 'RESULTS.md',
             *sorted((ROOT / 'docs' / 'results').glob('*/README.md'))]
    text = '\n'.join(page.read_text(encoding='utf-8') for page in pages)
    # a name's start: not inside a longer one (a campaign's tasks/cma-whole.yaml)
    presets = set(re.findall(r'(?<![\w-])(?:config/(?:tasks|reproduce|stand-ins)/)?(\w+\.yaml)',
                             text))
    presets -= {'smaller.yaml', 'campaign.yaml'}
    assert {'task5.yaml', 'task6.yaml', 'task5_along_x.yaml', 'task6_diagonal.yaml'} <= presets
    for name in sorted(presets):
        found = [folder / name for folder in (ROOT / 'config' / 'tasks',
                                              ROOT / 'config' / 'reproduce',
                                              ROOT / 'config' / 'stand-ins')
                 if (folder / name).exists()]
        assert found, f'the results pages name {name}, which is in no config folder'
        for path in found:
            load_task(path)
    for table in set(re.findall(r'(?:docs/)?(results/[\w.-]+/[\w.-]+\.(?:md|csv|png))', text)):
        assert (ROOT / 'docs' / table).exists(), f'the results pages name a missing {table}'


@pytest.mark.system
def test_seeds_are_a_count_a_range_or_a_list(capsys):
    assert definition.parse_seeds('3') == (1, 2, 3)  # the tuning seeds
    assert definition.parse_seeds('101-105') == (101, 102, 103, 104, 105)  # fresh seeds
    assert definition.parse_seeds('4,7,4') == (4, 7)
    assert definition.seeds_text((101, 102, 103)) == 'seeds 101 to 103'
    assert definition.seeds_text((4, 7)) == 'seeds 4, 7'
    for bad in ('0', '5-x', '', '3-1'):
        assert cli.main(['reproduce', 'levers-task6', '--seeds', bad]) == 2
        error = capsys.readouterr().err.strip()
        assert error.count('\n') == 0 and '--seeds' in error and repr(bad) in error
    assert cli.main(['reproduce', 'levers-task6', '--seeds', '9-1']) == 2
    assert 'a range runs upwards: 1-9' in capsys.readouterr().err
    # A bare 105 is a user who wants seed 105, not 105 runs of every configuration.
    assert cli.main(['reproduce', 'levers-task6', '--seeds', '105']) == 2
    error = capsys.readouterr().err.strip()
    assert error.count('\n') == 0 and '105-105' in error and '1-105' in error
    assert definition.parse_seeds('1-105') == tuple(range(1, 106))
