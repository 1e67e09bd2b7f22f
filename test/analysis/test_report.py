"""`hand-codesign analyze`: the report folder of a real run, its CSV against the bag, bad bags."""

import copy
import csv

from analysis_run import copy_bag
from analysis_run import decoded_messages
from analysis_run import run_cli
from analysis_run import TASK
from bag_samples import sample_messages
from bag_samples import write_bag
from hand_codesign.analysis.report import default_report_dir
from hand_codesign.cli import main
from hand_codesign.core.run.runs import run_task
from hand_codesign.core.task.genome import genome_spec
from hand_codesign.ros import topics
from hand_codesign.version import version_text
from mcap.writer import Writer
import numpy as np
import pytest


def read_csv(path):
    with open(path, newline='', encoding='utf-8') as stream:
        return list(csv.DictReader(stream))


@pytest.fixture(scope='module')
def report(real_run, tmp_path_factory):
    out = tmp_path_factory.mktemp('report') / 'report'
    assert main(['analyze', str(real_run.bag), '--out', str(out)]) == 0
    return out


@pytest.mark.system
def test_analyze_writes_every_file(real_run, report):
    for name in ('evaluations.csv', 'generations.csv', 'convergence.png', 'report.md'):
        assert (report / name).stat().st_size > 0, name
    assert (report / 'convergence.png').read_bytes().startswith(b'\x89PNG')
    assert not (report / 'pareto.png').exists()   # a CMA-ES run has no Pareto front
    text = (report / 'report.md').read_text()
    result = real_run.result
    # the version (and commit) of what wrote the report, as `hand-codesign --version` says
    assert f'| report by | hand-codesign {version_text()} |' in text
    for fact in ('task5', '| seed | 3 |', '4 generations x 6 candidates x 2 world states',
                 'evaluations per second', '![convergence.png](convergence.png)',
                 f'Candidate {result["best_candidate_id"]} of generation {result["generation"]}'):
        assert fact in text, fact
    # the best design's parameters in physical units, as the optimizer reported them
    for name, value in result['design'].items():
        assert f'| {name} | {value:.6g} |' in text, name


@pytest.mark.system
def test_report_shows_the_best_design_at_the_start_and_end_of_world_0(report):
    import imageio.v3 as imageio
    text = (report / 'report.md').read_text()
    assert '](best_design.png)' in text.split('## Best design')[1]
    image = imageio.imread(report / 'best_design.png')[..., :3].astype(int)
    start, end = np.array_split(image, 2, axis=1)
    assert start.std() > 10 and end.std() > 10    # something is drawn in both panels


def test_design_picture_places_each_shape_at_its_pose():
    from hand_codesign.analysis.design_picture import shape_surfaces
    from hand_codesign.core.sim.geometry import Shape
    from hand_codesign.core.rotations import axis_angle_quaternion
    # a 4 x 2 x 1 cm box turned 90 degrees about z: 2 cm along x, 4 cm along y
    box = Shape('box', 'object', (0.1, 0.2, 0.3), axis_angle_quaternion((0, 0, 1), np.pi / 2),
                (0.04, 0.02, 0.01), (0, 0, 1, 1))
    points = np.concatenate([grid.reshape(3, -1).T for grid in shape_surfaces(box)])
    assert np.allclose(points.min(axis=0), [0.09, 0.18, 0.295])
    assert np.allclose(points.max(axis=0), [0.11, 0.22, 0.305])
    sphere = Shape('sphere', 'segments', (0.0, 0.0, 0.1), (0, 0, 0, 1), (0.02,) * 3,
                   (1, 0, 0, 1))
    points = shape_surfaces(sphere)[0].reshape(3, -1).T
    assert np.allclose(np.linalg.norm(points - [0.0, 0.0, 0.1], axis=1), 0.01)


@pytest.mark.system
def test_csv_rows_are_the_bag_evaluations_bit_for_bit(real_run, report):
    rows = read_csv(report / 'evaluations.csv')
    evaluations = decoded_messages(real_run.mcap, topics.EVALUATIONS)
    candidates = {c.candidate_id: c for c in decoded_messages(real_run.mcap, topics.CANDIDATES)}
    assert len(rows) == len(evaluations) >= 24
    for row, message in zip(rows, evaluations):
        assert int(row['candidate_id']) == message.candidate_id
        assert int(row['generation']) == message.generation
        assert row['evaluator'] == message.evaluator_id
        assert row['status'] in ('ok', 'duplicate')
        for name, value in zip(message.objective_names, message.objectives):
            assert float(row[name]) == value
        assert float(row['fitness']) == message.fitness
        assert row['collision'] == ('true' if message.collision else 'false')
        assert int(row['unstable_worlds']) == message.unstable_worlds
        assert float(row['simulated_time']) == message.simulated_time
        assert float(row['wall_time']) == message.wall_time
        candidate = candidates[message.candidate_id]
        for name, value in zip(candidate.genome_names, candidate.genome):
            assert float(row[name]) == value
    best_id = real_run.result['best_candidate_id']
    best = [row for row in rows if int(row['candidate_id']) == best_id]
    assert float(best[0]['fitness']) == real_run.result['fitness']


@pytest.mark.system
def test_generations_csv_follows_the_summaries(real_run, report):
    rows = read_csv(report / 'generations.csv')
    assert [int(row['generation']) for row in rows] == [0, 1, 2, 3]
    summaries = [s for s in decoded_messages(real_run.mcap, topics.GENERATION_SUMMARY)
                 if not s.final]
    for row, summary in zip(rows, summaries):
        assert float(row['best_position_1']) == summary.best[0]
        assert float(row['median_position_1']) == summary.median[0]
    assert float(rows[-1]['best_fitness_so_far']) == real_run.result['fitness']


@pytest.mark.system
def test_terminal_summary_and_default_folder(real_run, tmp_path, capsys):
    bag = tmp_path / 'copy.mcap'
    copy_bag(real_run.mcap, bag)
    assert main(['analyze', str(bag)]) == 0
    printed = capsys.readouterr().out
    assert f'best design: candidate {real_run.result["best_candidate_id"]}' in printed
    assert 'evaluations per second' in printed and 'median position_1' in printed
    assert default_report_dir(bag) == tmp_path / 'copy_report'
    assert (tmp_path / 'copy_report' / 'report.md').exists()


def test_mocma_run_gets_its_pareto_fronts(tmp_path):
    messages = sample_messages(generations=4, population=6)
    messages[topics.RUN_INFO][0].algorithm = 'mocma'
    messages[topics.RUN_INFO][0].objective_names = ['position_1', 'orientation_1']
    for index, summary in enumerate(messages[topics.GENERATION_SUMMARY]):
        front = np.array([[0.1, 0.5], [0.2, 0.3], [0.4, 0.1]]) / (index + 1)
        summary.pareto_size = len(front)
        summary.pareto_front = front.ravel().tolist()
    bag = tmp_path / 'mocma.mcap'
    write_bag(bag, messages)
    out = tmp_path / 'report'
    assert main(['analyze', str(bag), '--out', str(out)]) == 0
    assert (out / 'pareto.png').read_bytes().startswith(b'\x89PNG')
    front = read_csv(out / 'pareto_front.csv')
    assert [(float(r['position_1']), float(r['orientation_1'])) for r in front] == [
        (0.1 / 4, 0.5 / 4), (0.2 / 4, 0.3 / 4), (0.4 / 4, 0.1 / 4)]
    assert '![pareto.png](pareto.png)' in (out / 'report.md').read_text()


# -------------------------------------------------------------------- bad bags

@pytest.mark.system
def test_empty_file_gives_one_clear_line(tmp_path):
    bag = tmp_path / 'empty.mcap'
    bag.write_bytes(b'')
    process = run_cli('analyze', bag)
    assert process.returncode == 2
    assert 'Traceback' not in process.stderr
    assert f'{bag}: empty file; expected an MCAP bag' in process.stderr


def test_file_that_is_not_mcap(tmp_path, capsys):
    bag = tmp_path / 'notes.mcap'
    bag.write_text('just some text\n')
    assert main(['analyze', str(bag)]) == 2
    assert 'not an MCAP file' in capsys.readouterr().err


def test_bag_of_another_program(tmp_path, capsys):
    bag = tmp_path / 'other.mcap'
    with open(bag, 'wb') as stream:
        writer = Writer(stream)
        writer.start(profile='ros2', library='another program')
        schema = writer.register_schema('std_msgs/msg/String', 'ros2msg', b'string data\n')
        channel = writer.register_channel('/chatter', 'cdr', schema)
        writer.add_message(channel, log_time=1, publish_time=1,
                           data=b'\x00\x01\x00\x00\x06\x00\x00\x00hello\x00')
        writer.finish()
    assert main(['analyze', str(bag)]) == 2
    error = capsys.readouterr().err
    assert 'an MCAP file without hand_codesign topics' in error
    assert '/chatter [std_msgs/msg/String]' in error


def test_missing_bag(tmp_path, capsys):
    assert main(['analyze', str(tmp_path / 'nothing')]) == 2
    assert 'no such file or directory' in capsys.readouterr().err


@pytest.mark.system
def test_truncated_bag_is_read_up_to_the_cut(real_run, tmp_path, capsys):
    data = real_run.mcap.read_bytes()
    bag = tmp_path / 'cut.mcap'
    bag.write_bytes(data[:int(len(data) * 0.7)])   # a recorder killed mid-write
    out = tmp_path / 'report'
    assert main(['analyze', str(bag), '--out', str(out)]) == 0
    captured = capsys.readouterr()
    assert 'is truncated (its recorder was probably killed)' in captured.err
    assert 'truncated: read up to the cut' in captured.out
    rows = read_csv(out / 'evaluations.csv')
    assert 0 < len(rows) <= len(decoded_messages(real_run.mcap, topics.EVALUATIONS))
    assert 'truncated' in (out / 'report.md').read_text()


@pytest.mark.system
def test_bag_cut_before_the_run_started(real_run, tmp_path, capsys):
    bag = tmp_path / 'early.mcap'
    copy_bag(real_run.mcap, bag, keep=lambda topic, *_: topic == topics.EVALUATOR_STATUS)
    out = tmp_path / 'report'
    assert main(['analyze', str(bag), '--out', str(out)]) == 0
    captured = capsys.readouterr()
    assert 'no RunInfo' in captured.err
    assert '(no generation finished)' in captured.out
    assert read_csv(out / 'evaluations.csv') == []


@pytest.mark.system
def test_gene_columns_are_the_task_genes(report):
    header = (report / 'evaluations.csv').read_text().splitlines()[0].split(',')
    names = genome_spec(run_task(TASK.read_text(), str(TASK), 3, 4, 6, 2)).names
    assert header[-len(names):] == names


def test_rejections_and_duplicate_answers_are_marked(tmp_path):
    messages = sample_messages(generations=2, population=6)
    evaluations = messages[topics.EVALUATIONS]
    evaluations.append(copy.deepcopy(evaluations[2]))     # a late second answer
    bag = tmp_path / 'sample.mcap'
    write_bag(bag, messages)
    out = tmp_path / 'report'
    assert main(['analyze', str(bag), '--out', str(out)]) == 0
    rows = read_csv(out / 'evaluations.csv')
    assert [row['status'] for row in rows].count('duplicate') == 1
    rejected = [row for row in rows if row['status'] == 'rejected']
    assert len(rejected) == 1 and rejected[0]['candidate_id'] == '5'
    assert rejected[0]['reason'] == 'genome has NaN — rejected'
    assert rejected[0]['position_1'] == rejected[0]['fitness'] == ''
    assert '11 ok, 1 rejected, 1 duplicate' in (out / 'report.md').read_text()
