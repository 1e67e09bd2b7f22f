"""The run controller without ROS: a whole run driven by events and a fake clock."""

import json
import pathlib

from hand_codesign.core.run.controller import RunController
from hand_codesign.core.run.controller import write_result
from hand_codesign.core.run.runs import load_run_task
from hand_codesign.core.search.resume import rebuild_search
from hand_codesign.core.search.search import Search
import numpy as np
import yaml

ROOT = pathlib.Path(__file__).resolve().parents[3]
TASKS = ROOT / 'config' / 'tasks'
RUN = 'run-1'


def objectives_of(x, size):
    """Return a cheap objective vector that depends on every value of a genome."""
    x = np.asarray(x, dtype=float)
    return np.array([np.sum((x - 0.3 - 0.1 * index) ** 2) for index in range(size)])


class Clock:
    """A clock that moves only when the test says so."""

    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now


class Outbox:
    """What the controller sends, kept in order, as a node would publish it."""

    def __init__(self):
        self.candidates = []   # (candidate, evaluator, attempt, genome_names, world_states)
        self.summaries = []
        self.lines = []        # (level, text)
        self.result = None

    def send_candidate(self, candidate, evaluator_id, attempt, genome_names, design):
        self.candidates.append((candidate, evaluator_id, attempt, genome_names,
                                candidate.variant.world_states))

    def send_summary(self, summary):
        self.summaries.append(summary)

    def log(self, text, level='info'):
        self.lines.append((level, text))

    def finish(self, result):
        self.result = result

    def take(self):
        sent, self.candidates = self.candidates, []
        return sent


def task5(**budget):
    budget = {'iterations': 3, 'population': 6, 'world_states': 3, **budget}
    return load_run_task(TASKS / 'task5.yaml', 7, budget['iterations'], budget['population'],
                         budget['world_states'])


def start(task, clock, evaluators=('a', 'b'), resumed=None, **options):
    outbox = Outbox()
    controller = RunController(task, RUN, outbox, resumed=resumed, clock=clock,
                               evaluators_expected=len(evaluators), **options)
    for evaluator in evaluators:
        controller.heard_from(evaluator, 2)
    controller.tick()
    return controller, outbox


def answer_everything(controller, outbox, size, clock):
    """Answer every candidate sent, the latest first, until the run finishes."""
    while outbox.result is None:
        sent = outbox.take()
        assert sent, 'the controller stopped sending before the run finished'
        for candidate, evaluator, _, _, _ in reversed(sent):
            clock.now += 0.5
            controller.evaluated(RUN, candidate.candidate_id, evaluator,
                                 objectives_of(candidate.x, size), 0.5)
            controller.heard_from(evaluator, 2)   # an evaluator's status after each answer


def plain_loop(task, known=None):
    """Run the search of task directly, ask / tell, with the same objectives."""
    search = Search(task)
    size = len(task.objective_names)
    while not search.stop():
        search.tell({c.candidate_id: objectives_of(c.x, size) for c in search.ask()})
    return search


def test_a_run_reaches_the_result_of_a_plain_ask_tell_loop(tmp_path):
    task, clock = task5(), Clock()
    controller, outbox = start(task, clock)
    answer_everything(controller, outbox, len(task.objective_names), clock)
    expected, structure = plain_loop(task).best
    result = outbox.result
    assert result['best_candidate_id'] == expected.candidate_id
    assert result['fitness'] == expected.fitness
    assert result['evaluations'] == 18 and result['stop_reason'] == 'maxiter=3'
    assert [s['final'] for s in outbox.summaries] == [False, False, False, True]
    assert [s['generation'] for s in outbox.summaries[:3]] == [0, 1, 2]
    assert np.array_equal(outbox.summaries[-1]['best_x'], expected.x)
    assert sum('generation 3/3' in text for _, text in outbox.lines) == 1
    path = tmp_path / 'result.json'
    write_result(path, result, {'candidates': 18})
    written = json.loads(path.read_text())
    assert written['published'] == {'candidates': 18}
    assert written['objectives']['position_1'] == expected.objectives[0]
    assert len(written['design']) == 24


def test_nothing_is_sent_before_the_evaluators_and_subscribers_are_there():
    clock = Clock()
    outbox = Outbox()
    controller = RunController(task5(), RUN, outbox, evaluators_expected=2, clock=clock)
    controller.heard_from('a', 2)
    controller.tick()
    assert outbox.candidates == [] and controller.started is None
    controller.heard_from('b', 2)
    controller.tick(subscribers_ready=False)
    assert outbox.candidates == []
    controller.tick()
    assert len(outbox.candidates) == 4     # capacity 2 each
    assert ('info', 'evaluators ready, starting') in outbox.lines


def test_candidates_of_a_silent_evaluator_go_to_another():
    clock = Clock()
    controller, outbox = start(task5(), clock, heartbeat_timeout=5.0)
    first = outbox.take()
    of_a = sorted(c.candidate_id for c, evaluator, _, _, _ in first if evaluator == 'a')
    clock.now += 6.0
    controller.heard_from('b', 2)          # b lives on; a fell silent
    for candidate, evaluator, _, _, _ in first:
        if evaluator == 'b':
            controller.evaluated(RUN, candidate.candidate_id, 'b', [1.0], 0.1)
    resent = outbox.take()
    assert all(evaluator == 'b' for _, evaluator, _, _, _ in resent)
    assert sorted(c.candidate_id for c, _, attempt, _, _ in resent if attempt == 1) == of_a


def test_the_adaptive_deadline_follows_the_slowest_evaluation():
    clock = Clock()
    controller, outbox = start(task5(), clock, evaluators=('a', 'b', 'c'),
                               heartbeat_timeout=1000.0)
    first = outbox.take()
    done, waiting = first[0], first[1]
    controller.evaluated(RUN, done[0].candidate_id, done[1], [1.0], 10.0)
    outbox.take()
    for seconds in (150.0, 51.0):          # 20 x 10 s = 200 s after it was sent
        clock.now += seconds
        for evaluator in ('a', 'b', 'c'):
            controller.heard_from(evaluator, 4)   # room for what is sent again
        resent = [c.candidate_id for c, _, attempt, _, _ in outbox.take() if attempt == 1]
        assert (waiting[0].candidate_id in resent) == (seconds == 51.0)


def test_a_rejected_candidate_goes_to_another_evaluator():
    clock = Clock()
    controller, outbox = start(task5(), clock)
    sent = outbox.take()
    candidate, evaluator, _, _, _ = sent[0]
    controller.rejected(RUN, candidate.candidate_id, evaluator, 'no PyBullet here')
    other = {'a': 'b', 'b': 'a'}[evaluator]
    controller.heard_from(evaluator, 2)
    assert outbox.take() == [], 'sent back to the evaluator that refused it'
    busy = next(c for c, e, _, _, _ in sent if e == other)
    controller.evaluated(RUN, busy.candidate_id, other, [1.0], 0.1)   # other has room now
    resent = outbox.take()
    assert [(c.candidate_id, e, attempt) for c, e, attempt, _, _ in resent][0] == (
        candidate.candidate_id, other, 1)
    assert ('warning', f'candidate {candidate.candidate_id} rejected by {evaluator}: '
                       'no PyBullet here') in outbox.lines


def test_messages_of_another_run_change_nothing():
    clock = Clock()
    controller, outbox = start(task5(population=4), clock)
    sent = outbox.take()
    controller.heard_from('intruder', 8, run_id='other-run')
    for candidate, evaluator, _, _, _ in sent:
        controller.evaluated('other-run', candidate.candidate_id, evaluator, [0.0], 0.1)
        controller.rejected('other-run', candidate.candidate_id, evaluator, 'nope')
    assert outbox.summaries == [] and outbox.lines[-1] == ('info', 'evaluators ready, starting')
    assert 'intruder' not in controller.dispatcher.evaluators


def test_a_resumed_run_sends_only_what_its_record_lacks_and_ends_alike():
    task = task5(iterations=4)
    uninterrupted = plain_loop(task).best[0]
    # the record of an interrupted run: two generations and 2 answers of the third
    search, recorded, genomes = Search(task), {}, {}
    for batch in range(3):
        for candidate in search.ask()[:6 if batch < 2 else 2]:
            recorded[candidate.candidate_id] = objectives_of(candidate.x,
                                                             len(task.objective_names))
            genomes[candidate.candidate_id] = candidate.x
        if batch < 2:
            search.tell({i: recorded[i] for i in (c.candidate_id for c in search.ask())})
    point = rebuild_search(task, 'old-run', 'the record', recorded, genomes)
    assert point.evaluations_told == 12 and sorted(point.known) == [12, 13]
    clock = Clock()
    controller, outbox = start(task, clock, resumed=point)
    assert controller.run_info()['resumed_from'] == 'old-run'
    first = [c.candidate_id for c, _, _, _, _ in outbox.candidates]
    assert 12 not in first and 13 not in first
    answer_everything(controller, outbox, len(task.objective_names), clock)
    assert outbox.result['best_candidate_id'] == uninterrupted.candidate_id
    assert outbox.result['fitness'] == uninterrupted.fitness
    assert outbox.result['evaluations'] == 24


def test_a_resumed_runs_rate_and_time_left_count_only_what_it_evaluated():
    task = task5(iterations=4)
    search, recorded, genomes = Search(task), {}, {}
    for _ in range(2):
        batch = search.ask()
        for candidate in batch:
            recorded[candidate.candidate_id] = objectives_of(candidate.x,
                                                             len(task.objective_names))
            genomes[candidate.candidate_id] = candidate.x
        search.tell({c.candidate_id: recorded[c.candidate_id] for c in batch})
    point = rebuild_search(task, 'old-run', 'the record', recorded, genomes)
    clock = Clock()
    controller, outbox = start(task, clock, resumed=point, audit_fraction=0.0)
    answer_everything(controller, outbox, len(task.objective_names), clock)
    # generation 3: 6 answers in 3 s here (the record's 12 took no time here), so 2 per second
    # and 3 s for the last 6
    line = next(text for _, text in outbox.lines if text.startswith('generation 3/4'))
    assert '| 18 evaluations, 2.0/s |' in line and line.endswith('about 3 s left')


def test_a_hierarchy_checks_each_structure_on_its_evaluation_worlds():
    task = load_run_task(TASKS / 'task4.yaml', 3, 1, 4, 2)
    clock = Clock()
    controller, outbox = start(task, clock)
    size = len(task.objective_names)
    checks, sent_all = [], []
    while outbox.result is None:
        sent = outbox.take()
        sent_all += sent
        checks += [world_states for _, _, _, _, world_states in sent if world_states]
        for candidate, evaluator, _, _, _ in sent:
            controller.evaluated(RUN, candidate.candidate_id, evaluator,
                                 objectives_of(candidate.x, size), 0.1)
    assert checks and all(w == task.hierarchy.evaluation_world_states for w in checks)
    check_lines = [text for _, text in outbox.lines if 'best design on the held-out' in text]
    seeds = plain_loop(task).outcomes[0].seeds
    assert check_lines[0].startswith(f'structure [1] (optimized with seeds {seeds[0]}, '
                                     f'{seeds[1]}): best design on the held-out worlds')
    assert all(candidate.variant.held_out for candidate, _, _, _, w in sent_all if w)
    best, structure = plain_loop(task).best
    assert outbox.result['best_candidate_id'] == best.candidate_id
    assert outbox.result['structure'] == list(structure)


def test_a_two_stage_run_resumed_in_stage_two_ends_as_the_uninterrupted_run():
    task = load_run_task(TASKS / 'task1.yaml', 4, 2, 4, 2)
    assert task.two_stage
    size = len(task.objective_names)
    uninterrupted = plain_loop(task).best[0]
    # the record of a run interrupted after stage 1 and one answer of stage 2
    search, recorded, genomes = Search(task), {}, {}
    while search.stage == 1:
        batch = search.ask()
        recorded.update({c.candidate_id: objectives_of(c.x, size) for c in batch})
        genomes.update({c.candidate_id: c.x for c in batch})
        search.tell({c.candidate_id: recorded[c.candidate_id] for c in batch})
    first = search.ask()[0]
    recorded[first.candidate_id], genomes[first.candidate_id] = objectives_of(first.x, size), \
        first.x
    point = rebuild_search(task, 'old-run', 'the record', recorded, genomes)
    assert point.search.stage == 2 and list(point.known) == [first.candidate_id]
    clock = Clock()
    controller, outbox = start(task, clock, resumed=point)
    sent = outbox.candidates
    assert {c.variant.stage for c, _, _, _, _ in sent} == {2}
    assert first.candidate_id not in [c.candidate_id for c, _, _, _, _ in sent]
    answer_everything(controller, outbox, size, clock)
    assert outbox.result['best_candidate_id'] == uninterrupted.candidate_id
    assert outbox.result['fitness'] == uninterrupted.fitness
    assert outbox.result['stop_reason'] == 'stage=2, maxiter=2'


def test_a_resampled_run_sends_each_generations_draw_and_reports_its_final_check(tmp_path):
    document = yaml.safe_load((TASKS / 'task5.yaml').read_text())
    document['worlds'] = {'resample': 'generation', 'final_check': 2}
    path = tmp_path / 'resampled.yaml'
    path.write_text(yaml.safe_dump(document))
    task, clock = load_run_task(path, 7, 3, 6, 3), Clock()
    controller, outbox = start(task, clock)
    sent_all = []
    while outbox.result is None:
        sent = outbox.take()
        sent_all += sent
        for candidate, evaluator, _, _, _ in sent:
            # the objectives depend on the draw: each is easier than the one before
            offset = 1.0 / candidate.variant.world_draw if candidate.variant.world_draw else 0.0
            controller.evaluated(RUN, candidate.candidate_id, evaluator,
                                 objectives_of(candidate.x, 2) + offset, 0.1)
    draws = {candidate.candidate_id: candidate.variant.world_draw for candidate, *_ in sent_all}
    assert [draws[i] for i in range(20)] == [1] * 6 + [2] * 6 + [3] * 6 + [0, 0]
    assert all(world_states == 0 for *_, world_states in sent_all)  # the run's count
    result = outbox.result
    checked = result['final_check']
    assert [entry['candidate_id'] for entry in checked] == [18, 19]
    assert result['best_candidate_id'] == min(checked, key=lambda e: e['fitness'])[
        'candidate_id']
    assert result['evaluations'] == 20 and result['stop_reason'] == 'maxiter=3, final_check=2'
    # generations, the check (a check row, as a hierarchy's), then the final summary
    assert [s['check'] for s in outbox.summaries] == [False, False, False, True, False]
    final = outbox.summaries[-1]
    assert final['final'] and final['best_id'] == result['best_candidate_id']
    assert outbox.summaries[3]['best_id'] == result['best_candidate_id']
    assert any(text.startswith('final check on the fixed worlds of the best designs of the '
                               f'last 2 generations: candidate {result["best_candidate_id"]} ')
               for _, text in outbox.lines)
