"""
GenerationSummaries forged on a run's domain change neither its resume nor its report.

The session's real run is signed: its RunInfo announces the Ed25519 key its summaries are
signed with (core.run.signing). A forger on the domain copies the run id from the latched RunInfo
and publishes six summaries claiming objectives of 0 after the run's last one, and publishes a
genuine summary again; here they are appended to copies of the bag as the recorder would have
recorded them. Every reader (bag.reader.read_run: analyze, resume, replay, reproduce) leaves
them out and counts them; analyze says so.
"""

import copy

from analysis_run import copy_bag
from analysis_run import decoded_messages
from analysis_run import raw_messages
from analysis_run import run_cli
from hand_codesign.analysis.resume import resume_point
from hand_codesign.bag.reader import read_run
from hand_codesign.core.run.signing import summary_valid
from hand_codesign.core.run.signing import SummaryKey
from hand_codesign.ros import topics
from hand_codesign_msgs.msg import GenerationSummary
from hand_codesign_msgs.msg import RunInfo
import numpy as np
import pytest
from rclpy.serialization import deserialize_message
from test_resume import interrupted_copy

pytestmark = pytest.mark.system

FORGED = 6


def summaries_of(mcap):
    """Return the GenerationSummaries of a bag file as rclpy messages."""
    return [deserialize_message(data, GenerationSummary)
            for topic, _, _, data in raw_messages(mcap) if topic == topics.GENERATION_SUMMARY]


def forgeries(real_run):
    """Return the forger's messages: six summaries claiming 0, and a genuine one again."""
    summaries = summaries_of(real_run.mcap)
    last = summaries[-1]
    forged = []
    for number in range(1, FORGED + 1):
        summary = copy.deepcopy(last)   # the genuine signature, on other contents
        summary.generation = last.generation + number
        summary.best_fitness = 0.0
        summary.best_objectives = [0.0] * len(last.best_objectives)
        summary.best = [0.0] * len(last.best)
        summary.told_objectives = [0.0] * len(last.told_objectives)
        summary.wall_time = 1.0
        forged.append((topics.GENERATION_SUMMARY, summary))
    return forged + [(topics.GENERATION_SUMMARY, summaries[0])]


def test_the_run_signs_its_summaries(real_run):
    record = read_run(real_run.bag)
    key = bytes(record_key(real_run))
    assert len(key) == 32
    summaries = summaries_of(real_run.mcap)
    assert summaries and all(summary_valid(key, summary) for summary in summaries)
    assert record.rejected_summaries == 0 and not record.warnings


def record_key(real_run):
    (run_info,) = decoded_messages(real_run.mcap, topics.RUN_INFO)
    return run_info.summary_key


def test_forged_summaries_change_no_reading_and_are_counted(real_run, tmp_path):
    forged_bag = copy_bag(real_run.mcap, tmp_path / 'forged.mcap', extra=forgeries(real_run))
    clean, forged = read_run(real_run.bag), read_run(forged_bag)
    assert forged.rejected_summaries == FORGED + 1
    assert f'left out {FORGED + 1} GenerationSummary message(s)' in forged.warning
    for column in ('generation', 'best_fitness', 'wall_time', 'told_ids', 'evaluations'):
        assert np.array_equal(forged.generation_summaries[column],
                              clean.generation_summaries[column], equal_nan=True), column
    report = run_cli('analyze', forged_bag, '--out', tmp_path / 'report')
    assert report.returncode == 0, report.stderr
    clean_report = run_cli('analyze', real_run.bag, '--out', tmp_path / 'clean_report')
    text = (tmp_path / 'report' / 'report.md').read_text()
    assert f'{FORGED + 1} GenerationSummary message(s) in the bag failed' in report.stdout
    assert (tmp_path / 'report' / 'generations.csv').read_text() == (
        tmp_path / 'clean_report' / 'generations.csv').read_text()
    assert 'forged' in text and clean_report.returncode == 0


def test_a_forged_run_info_recorded_first_unlocks_nothing(real_run, tmp_path):
    # the recorder heard the forger's copies of the RunInfo (made after the run's own, without
    # a key or with the forger's) before the run's own
    (run_info,) = [deserialize_message(data, RunInfo) for topic, _, _, data
                   in raw_messages(real_run.mcap) if topic == topics.RUN_INFO]
    log_time, publish_time = next((log_time, publish_time) for topic, log_time, publish_time, _
                                  in raw_messages(real_run.mcap) if topic == topics.RUN_INFO)
    keyless, foreign_key = copy.deepcopy(run_info), copy.deepcopy(run_info)
    keyless.summary_key = []
    foreign_key.summary_key = list(SummaryKey().public)
    first = [(topics.RUN_INFO, copy_, log_time - 2 + number, publish_time + 1000 + number)
             for number, copy_ in enumerate((keyless, foreign_key))]
    forged_bag = copy_bag(real_run.mcap, tmp_path / 'forged.mcap', extra=forgeries(real_run),
                          first=first)
    record = read_run(forged_bag)
    assert record.rejected_summaries == FORGED + 1
    assert len(record.generation_summaries) == len(read_run(real_run.bag).generation_summaries)


def test_forged_summaries_change_no_resume(real_run, tmp_path):
    clean_bag, _ = interrupted_copy(real_run, tmp_path / 'interrupted.mcap')
    clean = resume_point(clean_bag)
    forged_bag = copy_bag(clean_bag, tmp_path / 'forged.mcap', extra=forgeries(real_run))
    forged = resume_point(forged_bag)
    assert read_run(forged_bag).rejected_summaries == FORGED + 1
    assert (forged.batches_told, forged.evaluations_told) == (
        clean.batches_told, clean.evaluations_told)
    assert sorted(forged.known) == sorted(clean.known)
    assert [(c.candidate_id, c.x.tolist()) for c in forged.to_evaluate] == [
        (c.candidate_id, c.x.tolist()) for c in clean.to_evaluate]
