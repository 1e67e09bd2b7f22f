"""Per-generation statistics of a run, as the optimizer node publishes and the report plots."""

import numpy as np

PROGRESS_PREFIX = 'generation '   # every progress_line starts so: a quiet run picks them out


def generation_summary(generation, structure, names, told_ids, objectives, result,
                       evaluations, wall_time, check=False, horizon=0.0):
    """
    Return the summary of one told batch as a plain dict.

    told_ids, objectives: the candidates of the batch and their (batch, num_objectives)
    values as told; result: the optimizer's OptimizerResult after the tell (best so far,
    Pareto front for MO-CMA-ES); check: the batch was a hierarchy structure's check;
    horizon: the sub-problem's horizon (s) the batch was evaluated on, 0 for none.
    """
    objectives = np.asarray(objectives, dtype=float).reshape(-1, len(names))
    front = getattr(result, 'pareto_objectives', np.zeros((0, len(names))))
    return {
        'generation': int(generation),
        'structure': tuple(int(joints) for joints in structure),
        'check': bool(check),
        'horizon': float(horizon),
        'told_ids': [int(candidate_id) for candidate_id in told_ids],
        'told_objectives': objectives,
        'names': tuple(names),
        'best': objectives.min(axis=0),
        'median': np.median(objectives, axis=0),
        'worst': objectives.max(axis=0),
        'pareto_front': np.asarray(front, dtype=float).reshape(-1, len(names)),
        'best_id': int(result.candidate_id),
        'best_objectives': np.asarray(result.objectives, dtype=float),
        'best_fitness': float(result.fitness),
        'best_x': np.asarray(result.x, dtype=float),
        'evaluations': int(evaluations),
        'wall_time': float(wall_time),
        'final': False,
        'stop_reason': '',
    }


def progress_line(summary, iterations, rate, seconds_left):
    """
    Return the one-line progress report of a generation for the terminal.

    rate: evaluations per second of this process; seconds_left: None while unknown (a resumed
    run whose first generation came whole from its record).
    """
    best = ', '.join(f'{name} {value:.4g}'
                     for name, value in zip(summary['names'], summary['best_objectives']))
    structure = 'x'.join(str(joints) for joints in summary['structure'])
    if summary.get('horizon'):
        structure += f', horizon {summary["horizon"]:g} s'
    stage = f' of stage {summary["stage"]}' if summary.get('stage') else ''
    position = f'{PROGRESS_PREFIX}{summary["generation"] + 1}/{iterations}{stage}'
    if summary.get('restart') is not None:
        # with restarts (core.search.restarts) the budget is in evaluations, not generations
        position = (f'{PROGRESS_PREFIX}{summary["generation"] + 1}{stage} (restart '
                    f'{summary["restart"]}, population {summary["population"]}; '
                    f'{summary["spent"]}/{summary["budget"]} evaluations)')
    return (f'{position} [{structure}] | '
            f'{summary["evaluations"]} evaluations, {rate:.1f}/s | best fitness '
            f'{summary["best_fitness"]:.4g} ({best}) | '
            + (f'about {format_duration(seconds_left)} left' if seconds_left is not None
               else 'time left not known yet'))


def format_duration(seconds):
    """Return a duration for people: e.g. '1 h 05 min', '12 min' or '40 s'."""
    seconds = int(round(seconds))
    if seconds < 60:
        return f'{seconds} s'
    minutes = seconds // 60
    if minutes < 60:
        return f'{minutes} min'
    return f'{minutes // 60} h {minutes % 60:02d} min'
