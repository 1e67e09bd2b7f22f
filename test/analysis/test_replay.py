"""`hand-codesign replay`: recorded objectives reproduced bit for bit, the animation, errors."""

import csv

from analysis_run import copy_bag
from analysis_run import run_cli
from hand_codesign.cli import main
from hand_codesign.ros import topics
import imageio.v3 as imageio
import numpy as np
import pytest

pytestmark = pytest.mark.system


def test_replay_of_the_best_design_is_bit_identical_and_animated(real_run, tmp_path, capsys):
    gif = tmp_path / 'best.gif'
    assert main(['replay', str(real_run.bag), '--gif', str(gif), '--world', '1']) == 0
    printed = capsys.readouterr().out
    assert f'replaying candidate {real_run.result["best_candidate_id"]} ' in printed
    assert 'replay reproduces the recorded objectives bit for bit' in printed
    assert repr(real_run.result['objectives']['position_1']) in printed
    rendered = int(printed.split(' frames of world 1)')[0].rsplit('(', 1)[1])
    assert rendered >= 30  # 1.5 s of frames; the GIF merges repeated frames of a still scene
    frames = imageio.imread(gif, index=None)
    assert frames.ndim == 4 and frames.shape[0] >= 2 and frames.shape[1:3] == (360, 480)
    assert np.any(frames[0] != frames[-1])                  # the hand moves
    assert len(np.unique(frames[frames.shape[0] // 2].reshape(-1, 3), axis=0)) > 20


def test_replay_of_a_ranked_design_of_a_generation(real_run, tmp_path, capsys):
    report = tmp_path / 'report'
    assert main(['analyze', str(real_run.bag), '--out', str(report)]) == 0
    with open(report / 'evaluations.csv', newline='') as stream:
        rows = [row for row in csv.DictReader(stream)
                if row['generation'] == '1' and row['status'] == 'ok']
    rows.sort(key=lambda row: (float(row['fitness']), int(row['candidate_id'])))
    capsys.readouterr()
    assert main(['replay', str(real_run.bag), '--generation', '1', '--rank', '2',
                 '--gif', str(tmp_path / 'ranked.gif')]) == 0
    printed = capsys.readouterr().out
    assert f'replaying candidate {rows[2]["candidate_id"]} of generation 1' in printed
    assert 'bit for bit' in printed


def test_replay_of_a_design_named_by_its_candidate_id(real_run, tmp_path, capsys):
    assert main(['replay', str(real_run.bag), '--candidate', '7',
                 '--gif', str(tmp_path / 'seven.gif')]) == 0
    printed = capsys.readouterr().out
    assert 'replaying candidate 7 of generation 1' in printed and 'bit for bit' in printed


def test_a_changed_recording_is_reported_loudly(real_run, tmp_path, capsys):
    best = real_run.result['best_candidate_id']

    def tamper(topic, message):
        if topic == topics.EVALUATIONS and message.candidate_id == best:
            message.objectives = ([np.nextafter(message.objectives[0], 1.0)]
                                  + list(message.objectives[1:]))
            return True
        return False

    bag = copy_bag(real_run.mcap, tmp_path / 'tampered.mcap', edit=tamper)
    assert main(['replay', str(bag), '--gif', str(tmp_path / 'x.gif')]) == 1
    captured = capsys.readouterr()
    assert 'REPLAY MISMATCH' in captured.err
    assert 'DIFFERENT' in captured.out


def test_gui_without_a_display_says_so(real_run):
    process = run_cli('replay', real_run.bag, '--gui')
    assert process.returncode == 2
    assert '--gui needs a display' in process.stderr
    assert 'Traceback' not in process.stderr


@pytest.mark.parametrize('flags, message', [
    (['--world', '7'], '--world 7: the run has 2 world states; expected 0 to 1'),
    (['--generation', '9'], 'no successful evaluation in generation 9 (generations in the '
                            'bag: 0..3)'),
    (['--generation', '0', '--rank', '6'], '--rank 6: generation 0 has 6 evaluated designs'),
    (['--candidate', '99'], 'candidate 99 is not in the bag'),
    (['--candidate', '7', '--rank', '1'], '--candidate 7 names one design: drop --generation'),
])
def test_bad_choices_are_user_errors(real_run, tmp_path, capsys, flags, message):
    assert main(['replay', str(real_run.bag), '--gif', str(tmp_path / 'x.gif')] + flags) == 2
    assert message in capsys.readouterr().err


def test_the_camera_can_look_up_through_the_table(real_run, tmp_path, capsys):
    # a hand above a box hides it from the default camera; from below the ground is not drawn
    side, below = tmp_path / 'side.gif', tmp_path / 'below.gif'
    assert main(['replay', str(real_run.bag), '--gif', str(side)]) == 0
    assert main(['replay', str(real_run.bag), '--gif', str(below), '--camera', '0,60']) == 0
    first = [imageio.imread(path, index=None)[0] for path in (side, below)]
    assert first[0].shape == first[1].shape and np.any(first[0] != first[1])


@pytest.mark.parametrize('value', ['60', '0,90', 'a,b'])
def test_a_bad_camera_is_one_line(real_run, tmp_path, value):
    process = run_cli('replay', real_run.bag, '--gif', tmp_path / 'x.gif', '--camera', value)
    assert process.returncode == 2 and 'Traceback' not in process.stderr
    assert process.stderr.strip().splitlines()[-1].startswith('hand-codesign replay: error: '
                                                              'argument --camera')
