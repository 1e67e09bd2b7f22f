"""
What the search sees on a task with early termination: plain eq. (6) against growing horizons.

Runs the same tiny search (same seed, population, worlds, generations) three ways on one task
and prints, per generation, the horizon, how many collision-free candidates there were and how
many distinct objective vectors they had (rounded to 6 significant digits), the spread of the
weighted fitness among them and the best fitness of the generation:

- `plain`: early termination at every check, as the task says without a horizon (eq. 6);
- `horizon`: the task's early_termination.horizon (core.search.horizon: no stop inside the
horizon);
- `horizon-stops`: the same horizons, but stopping at every check inside the horizon too.

At the end it evaluates each run's best design on the plain task and on the whole rollout
(eq. 5, no termination), so the three are compared on one yardstick, and prints the simulated
seconds per candidate of each run against the plain run's.

    python bench/bench_horizon.py [--task config/tasks/task3.yaml] [--seed 2]
        [--population 12] [--world-states 4] [--generations 10] [--start S] [--share F]
"""

import argparse
import dataclasses
import pathlib
import sys

from hand_codesign.core import TaskError
from hand_codesign.core.evaluate import COLLISION_PENALTY, evaluate
from hand_codesign.core.run.runs import load_run_task
from hand_codesign.core.search.search import Search
from hand_codesign.core.sim import objectives as objectives_module
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]


def distinct(rows):
    """Return how many distinct rows there are at 6 significant digits."""
    return len({tuple(float(f'{value:.6g}') for value in row) for row in rows})


def run(task, generations, stops_inside=False):
    """Run a search; return (per-generation lines, best x, simulated seconds per candidate)."""
    original = objectives_module.GoalSchedule._limit_to

    def keep_stops(schedule, horizon):
        termination = schedule.termination
        original(schedule, horizon)
        schedule.termination = termination[:schedule.num_checks]
        schedule._termination_list = tuple(bool(flag) for flag in schedule.termination)

    if stops_inside:
        objectives_module.GoalSchedule._limit_to = keep_stops
        objectives_module._SCHEDULES.clear()
    try:
        search = Search(task)
        lines, best, simulated, count = [], (np.inf, None), 0.0, 0
        for generation in range(generations):
            candidates = search.ask()
            batch_task = search.batch_task
            results = {c.candidate_id: evaluate(c.x, batch_task) for c in candidates}
            search.tell(results)
            fine = [r for r in results.values() if not r.collision]
            simulated += sum(r.simulated_time for r in results.values())
            count += len(results)
            fitness = np.array([r.fitness for r in fine])
            for candidate in candidates:
                result = results[candidate.candidate_id]
                if not result.collision and result.fitness < best[0]:
                    best = (result.fitness, candidate.x)
            lines.append(
                f'  {generation:3d}  horizon {search.horizons[-1] if search.horizons else 0:4.2f}'
                f'  free {len(fine):3d}  distinct {distinct([r.objectives for r in fine]):3d}'
                f'  spread {np.ptp(fitness) if len(fine) else 0:9.5f}'
                f'  best {fitness.min() if len(fine) else COLLISION_PENALTY:9.5f}')
        return lines, best[1], simulated / max(count, 1)
    finally:
        objectives_module.GoalSchedule._limit_to = original
        objectives_module._SCHEDULES.clear()


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--task', default=str(ROOT / 'config' / 'tasks' / 'task3.yaml'))
    parser.add_argument('--seed', type=int, default=2)
    parser.add_argument('--population', type=int, default=12)
    parser.add_argument('--world-states', type=int, default=4)
    parser.add_argument('--generations', type=int, default=10)
    parser.add_argument('--start', type=float, help="first horizon, s (default: the task's)")
    parser.add_argument('--share', type=float, help="share that must track (default: the task's)")
    args = parser.parse_args(argv)
    try:
        # one stage: the bench compares horizons, not the two stages of Tasks 1 and 2
        task = load_run_task(args.task, args.seed, args.generations, args.population,
                             args.world_states).replace(two_stage=False)
    except (OSError, TaskError) as error:
        print(f'bench_horizon: error: {error}', file=sys.stderr)
        return 2
    early = task.early_termination
    if early is None or early.horizon is None:
        print(f'bench_horizon: error: {args.task}: early_termination.horizon: expected a '
              'horizon to compare', file=sys.stderr)
        return 2
    spec = dataclasses.replace(early.horizon, **{
        key: value for key, value in (('start', args.start), ('share', args.share))
        if value is not None})
    horizon_task = task.replace(early_termination=dataclasses.replace(early, horizon=spec))
    plain_task = task.replace(early_termination=dataclasses.replace(early, horizon=None))
    whole_task = plain_task.replace(horizon=task.duration)
    print(f'{task.name}: seed {args.seed}, {args.generations} generations x '
          f'{args.population}, {args.world_states} worlds; horizon {spec}')
    reference = None
    for name, chosen, stops in (('plain', plain_task, False), ('horizon', horizon_task, False),
                                ('horizon-stops', horizon_task, True)):
        lines, best_x, seconds = run(chosen, args.generations, stops)
        reference = seconds if reference is None else reference
        print(f'{name}:')
        print('\n'.join(lines))
        if best_x is None:
            print('  no collision-free design')
            continue
        plain = evaluate(best_x, plain_task)
        whole = evaluate(best_x, whole_task)
        print(f'  best design: plain {plain.fitness:.5f} {np.round(plain.objectives, 5)}, '
              f'whole rollout {whole.fitness:.5f} {np.round(whole.objectives, 5)}; '
              f'{seconds:.3f} simulated s per candidate ({seconds / reference:.2f} x plain)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
