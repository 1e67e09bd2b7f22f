"""
An experiment's figures: errors at the start and end per configuration, and convergence.

Drawn with matplotlib (imported where a figure is drawn: a campaign that only runs loads no
plotting library); the file's suffix (.png, .svg, .pdf) is its format.
"""

from hand_codesign.analysis import records
from hand_codesign.analysis.generations import Generations, generations_from_summaries
from hand_codesign.campaign.experiment import run_key
from hand_codesign.campaign.folders import attempts
import numpy as np


def plot_errors(path, groups, tolerance, title, kinds=None):
    """
    Box plots of the pooled initial and final errors per group [(label, record list)].

    One panel per error kind (default: the tolerance's); the tolerance is drawn on its own.
    The file's suffix (.png, .svg, .pdf) is its format.
    """
    import matplotlib
    matplotlib.use('Agg')
    from matplotlib import pyplot
    kinds = kinds or (tolerance.kind,)
    width = max(6.0, 1.1 * len(groups) + 2)
    figure, axes = pyplot.subplots(1, len(kinds), figsize=(width * len(kinds), 4.5),
                                   squeeze=False)
    for axis, kind in zip(axes[0], kinds):
        scale, unit = {'orientation': (1.0, 'rad'), 'pose': (1.0, 'tolerances')}.get(
            kind, (1000.0, 'mm'))
        data, positions = [], []
        for index, (_, measured) in enumerate(groups):
            for offset, field in ((-0.18, 'initial_errors'), (0.18, 'errors')):
                data.append(np.concatenate([record['worlds'][field][kind]
                                            for record in measured]) * scale)
                positions.append(index + 1 + offset)
        boxes = axis.boxplot(data, positions=positions, widths=0.3, whis=(5, 95),
                             showfliers=False, patch_artist=True)
        for number, patch in enumerate(boxes['boxes']):
            patch.set_facecolor('lightgrey' if number % 2 == 0 else 'tab:blue')
        if kind == tolerance.kind:
            axis.axhline(tolerance.limit * scale, color='tab:red', linestyle='--',
                         linewidth=1, label=f'tolerance ({tolerance.describe()})')
            axis.legend(fontsize='small')
        axis.set_xticks(range(1, len(groups) + 1), [label for label, _ in groups],
                        rotation=30, ha='right', fontsize='small')
        axis.set_ylabel(f'{kind} error ({unit}), grey: start, blue: end')
        axis.grid(True, axis='y', alpha=0.3)
    figure.suptitle(f'{title}\nbox p25-p75, whiskers p5-p95, unseen worlds of every seed',
                    fontsize='medium')
    figure.tight_layout()
    figure.savefig(path, dpi=90)
    pyplot.close(figure)


def run_generations(bags):
    """Return (evaluations told, best fitness so far) over a run's bags, in order."""
    told, best = [], []
    for bag in bags:
        record = records.open_run(bag, warn=False)
        if not len(record.generation_summaries):
            continue
        names = records.objective_names_of(record)
        generations: Generations = generations_from_summaries(record, len(names))
        told += generations.evaluations.tolist()
        best += generations.best_fitness.tolist()
    return np.asarray(told, dtype=float), np.minimum.accumulate(np.asarray(best, dtype=float))


def convergence_panels(out, experiment, seeds):
    """Return (label, [(seed, (told, best))]) of each configuration with runs of `seeds`."""
    panels = []
    for configuration in experiment.configurations:
        curves = [(seed, run_generations(attempts(out / 'runs', run_key(configuration, seed))))
                  for seed in seeds]
        if any(len(told) for _, (told, _) in curves):  # `--only` leaves the others unrun
            panels.append((f'{configuration.key} ({configuration.algorithm_name})', curves))
    return panels


def seed_band(curves):
    """
    Return (evaluations, 25th percentile, median, 75th percentile) of curves across seeds.

    curves: [(seed, (evaluations told, best fitness so far))]. Each seed's best so far is a
    step function of the evaluations: at every evaluation count any seed told, it is its value
    at the last count told up to there (held after the seed's run ended, which cannot improve
    it); NaN before its first, and left out of the percentiles there.
    """
    told = [np.asarray(values[0], dtype=float) for _, values in curves if len(values[0])]
    best = [np.asarray(values[1], dtype=float) for _, values in curves if len(values[0])]
    grid = np.unique(np.concatenate(told)) if told else np.zeros(0)
    steps = np.full((len(told), len(grid)), np.nan)
    for row, (seed_told, seed_best) in enumerate(zip(told, best)):
        order = np.argsort(seed_told, kind='stable')
        last = np.searchsorted(seed_told[order], grid, side='right') - 1
        steps[row] = np.where(last >= 0, seed_best[order][np.maximum(last, 0)], np.nan)
    with np.errstate(all='ignore'):
        low, middle, high = (np.nanpercentile(steps, q, axis=0) if len(told) else grid
                             for q in (25, 50, 75))
    return grid, low, middle, high


def plot_convergence(path, panels, title):
    """
    Best fitness so far against evaluations, every configuration on one shared axis.

    Per configuration (one colour): the median across seeds as a line and the band between
    the 25th and 75th percentiles, over thin lines of the seeds. The file's suffix (.png,
    .svg, .pdf) is its format.
    """
    import matplotlib
    matplotlib.use('Agg')
    from matplotlib import pyplot
    figure, axis = pyplot.subplots(figsize=(7.5, 4.8))
    for index, (label, curves) in enumerate(panels):
        colour = f'C{index % 10}'
        for _, (told, best) in curves:
            if len(told):
                axis.step(told, best, where='post', color=colour, linewidth=0.6, alpha=0.35)
        grid, low, middle, high = seed_band(curves)
        seeds = sum(1 for _, (told, _) in curves if len(told))
        axis.fill_between(grid, low, high, step='post', color=colour, alpha=0.2, linewidth=0)
        axis.step(grid, middle, where='post', color=colour, linewidth=2,
                  label=f'{label}: median of {seeds} seeds')
    axis.set_yscale('log')
    axis.set_xlabel('evaluations')
    axis.set_ylabel('best weighted fitness so far')
    axis.grid(True, alpha=0.3)
    axis.legend(fontsize='small')
    axis.set_title(f'{title}\nmedian across seeds, band: 25th to 75th percentile, thin: '
                   'each seed', fontsize='medium')
    figure.tight_layout()
    figure.savefig(path, dpi=90)
    pyplot.close(figure)
