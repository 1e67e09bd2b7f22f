"""
Runs whose processes die (`hand-codesign run` supervising them), compared with a clean run.

Each run is the small Task 5 run of test_system. What a user checks: the run finishes, prints
what happened, and its generation summaries are those of the clean run; the bag of a run whose
recorder was killed is closed, readable by rosbags, and holds every message of the run once.
"""

import json
import signal
import threading
import time

from hand_codesign.analysis.bag import read_run
import psutil
import pytest
from rosbags.rosbag2 import Reader
from test_system import finish
from test_system import start_run
from test_system import summaries
import yaml


@pytest.fixture(scope='module')
def clean_run(tmp_path_factory):
    bag = tmp_path_factory.mktemp('supervised') / 'clean'
    finish(start_run(bag, 1))
    return bag


class Watched:
    """A run started in the background whose output lines are collected as they come."""

    def __init__(self, bag, evaluators):
        self.process = start_run(bag, evaluators)
        self.lines = []
        self.reader = threading.Thread(target=lambda: self.lines.extend(self.process.stdout),
                                       daemon=True)
        self.reader.start()

    def output(self):
        return ''.join(self.lines)

    def wait_for(self, condition, timeout=120):
        deadline = time.monotonic() + timeout
        while True:
            found = condition()
            if found:
                return found
            assert time.monotonic() < deadline and self.process.poll() is None, self.output()
            time.sleep(0.02)

    def child(self, text):
        """Return the run's child process whose command line contains text, or None."""
        for process in psutil.Process(self.process.pid).children(recursive=True):
            try:
                if text in ' '.join(process.cmdline()):
                    return process
            except psutil.NoSuchProcess:
                pass
        return None

    def finish(self):
        self.process.wait(timeout=240)
        self.reader.join(timeout=10)
        assert self.process.returncode == 0, self.output()
        return self.output()


def test_evaluator_killed_during_start_up(clean_run, tmp_path):
    bag = tmp_path / 'start-up'
    run = Watched(bag, 2)
    victim = run.wait_for(lambda: run.child('evaluator_id:=evaluator-1 '))
    victim.send_signal(signal.SIGKILL)   # the run is still waiting for its evaluators
    output = run.finish()
    assert 'evaluator-1 exited (code -9); restarting it' in output
    assert 'evaluators ready, starting' in output
    assert summaries(bag) == summaries(clean_run)
    assert (bag / 'logs' / 'evaluator-1-r1.log').exists()


def test_recorder_killed_mid_run(clean_run, tmp_path):
    bag = tmp_path / 'recorder'
    run = Watched(bag, 2)
    run.wait_for(lambda: 'generation 1/3' in run.output())
    run.child('recorder_node').send_signal(signal.SIGKILL)
    output = run.finish()
    assert 'recorder exited (code -9); restarting it' in output
    assert summaries(bag) == summaries(clean_run)
    information = yaml.safe_load((bag / 'metadata.yaml').read_text())[
        'rosbag2_bagfile_information']
    assert information['relative_file_paths'] == ['recorder_0.mcap', 'recorder_1.mcap']
    with Reader(bag) as reader:     # rosbags takes it: every file closed and indexed
        assert sum(1 for _ in reader.messages()) == information['message_count']
    record = read_run(bag)
    assert not record.truncated
    published = json.loads((bag / 'result.json').read_text())['published']
    assert record.message_counts['/candidates'] == published['candidates']
    assert record.message_counts['/generation_summary'] == published['generation_summary']
    assert record.message_counts['/run_info'] == 1
    sent = list(zip(record.candidates['candidate_id'], record.candidates['attempt']))
    assert len(sent) == len(set(sent))
    answers = list(zip(record.evaluations['candidate_id'], record.evaluations['attempt'],
                       record.evaluations['evaluator_id']))
    assert len(answers) == len(set(answers))
    ok = record.evaluations.select(record.evaluations['status'] == 0)
    assert sorted(set(ok['candidate_id'])) == list(range(18))
    # each evaluator logs how many evaluations it published when it stops
    published_evaluations = sum(
        int(line.rsplit(' published ', 1)[1].split()[0])
        for log in (bag / 'logs').glob('evaluator-*.log')
        for line in log.read_text().splitlines() if ' published ' in line)
    assert record.message_counts['/evaluations'] == published_evaluations
