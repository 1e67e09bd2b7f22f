"""
An experiment's figures: errors at the start and end per configuration, and convergence.

Legible from two configurations to thirty:

- Errors: a box per configuration for the start and the end of the motion, configurations
  down the page (one row each, their names in full beside them), a panel per error kind: the
  figure grows in height with the configurations, not into a strip thousands of pixels wide.
- Convergence: up to ten configurations share one axis, one colour each (matplotlib's ten
  distinguishable ones); more get small multiples, a panel per configuration on the same
  axes, that configuration's median and band in colour over every other configuration's
  median in light grey, so each is read on its own and against the field.

Drawn with matplotlib (imported where a figure is drawn: a campaign that only runs loads no
plotting library); the file's suffix (.png, .svg, .pdf) is its format.
"""

from hand_codesign.analysis import records
from hand_codesign.analysis.figures import load_pyplot
from hand_codesign.analysis.generations import Generations, generations_from_summaries
from hand_codesign.campaign.experiment import run_key
from hand_codesign.campaign.folders import attempts
import numpy as np

SHARED_AXIS_MOST = 10     # configurations one axis shows apart by colour
COLUMNS = 5               # panels per row of the small multiples
ROW_INCHES = 0.32         # height of a configuration's row in the errors figure


def plot_errors(path, groups, tolerance, title, kinds=None):
    """
    Box plots of the pooled initial and final errors per group [(label, record list)].

    One panel per error kind (default: the tolerance's), configurations down the page, the
    tolerance a dashed line. Boxes p25-p75, whiskers p5-p95, over the unseen worlds of every
    seed.
    """
    pyplot = load_pyplot()
    kinds = kinds or (tolerance.kind,)
    height = max(3.0, ROW_INCHES * len(groups) + 1.8)
    figure, axes = pyplot.subplots(1, len(kinds), figsize=(6.5 * len(kinds), height),
                                   squeeze=False, sharey=True)
    rows = np.arange(len(groups))[::-1] + 1          # the first configuration on top
    for axis, kind in zip(axes[0], kinds):
        scale, unit = {'orientation': (1.0, 'rad'), 'pose': (1.0, 'tolerances')}.get(
            kind, (1000.0, 'mm'))
        data, positions, colours = [], [], []
        for row, (_, measured) in zip(rows, groups):
            for offset, field, colour in ((0.18, 'initial_errors', 'lightgrey'),
                                          (-0.18, 'errors', 'tab:blue')):
                data.append(np.concatenate([record['worlds'][field][kind]
                                            for record in measured]) * scale)
                positions.append(row + offset)
                colours.append(colour)
        boxes = axis.boxplot(data, positions=positions, widths=0.3, whis=(5, 95),
                             showfliers=False, patch_artist=True, orientation='horizontal')
        for patch, colour in zip(boxes['boxes'], colours):
            patch.set_facecolor(colour)
        line = ''
        if kind == tolerance.kind:
            axis.axvline(tolerance.limit * scale, color='tab:red', linestyle='--', linewidth=1)
            line = f'; red: the tolerance ({tolerance.describe()})'
        axis.set_yticks(rows, [label for label, _ in groups], fontsize='small')
        axis.set_ylim(0.4, len(groups) + 0.6)
        axis.set_xlabel(f'{kind} error ({unit}); grey: start, blue: end{line}')
        axis.grid(True, axis='x', alpha=0.3)
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
    Best fitness so far against evaluations, per configuration across its seeds.

    panels: [(label, [(seed, (evaluations told, best so far))])]. Per configuration: the
    median across seeds (seed_band) as a line and the band between the 25th and 75th
    percentiles, over thin lines of the seeds; one shared axis for up to SHARED_AXIS_MOST
    configurations, small multiples beyond.
    """
    pyplot = load_pyplot()
    bands = [seed_band(curves) for _, curves in panels]
    if len(panels) <= SHARED_AXIS_MOST:
        figure, axis = pyplot.subplots(figsize=(7.5, 4.8))
        for index, ((label, curves), lines) in enumerate(zip(panels, bands)):
            _draw(axis, curves, lines, f'C{index}', label)
        axis.legend(fontsize='small')
        axes = [axis]
    else:
        rows = -(-len(panels) // COLUMNS)
        figure, grid = pyplot.subplots(rows, COLUMNS, figsize=(3.2 * COLUMNS, 2.5 * rows),
                                       sharex=True, sharey=True, squeeze=False)
        axes = list(grid.flat)
        for index, ((label, curves), lines) in enumerate(zip(panels, bands)):
            for other, (grid_x, _, middle, _) in enumerate(bands):
                if other != index:
                    axes[index].step(grid_x, middle, where='post', color='lightgrey',
                                     linewidth=0.8)
            _draw(axes[index], curves, lines, 'tab:blue', None)
            axes[index].set_title(label, fontsize='small')
        for axis in axes[len(panels):]:
            axis.axis('off')
    for axis in axes[:len(panels)]:
        axis.set_yscale('log')
        axis.grid(True, alpha=0.3)
    figure.supxlabel('evaluations', fontsize='medium')
    figure.supylabel('best weighted fitness so far', fontsize='medium')
    figure.suptitle(f'{title}\nmedian across seeds, band: 25th to 75th percentile, thin: '
                    'each seed' + ("; grey: the other configurations' medians"
                                   if len(panels) > SHARED_AXIS_MOST else ''),
                    fontsize='medium')
    figure.tight_layout()
    figure.savefig(path, dpi=90)
    pyplot.close(figure)


def _draw(axis, curves, lines, colour, label):
    """Draw one configuration: its seeds thin, its band, its median."""
    for _, (told, best) in curves:
        if len(told):
            axis.step(told, best, where='post', color=colour, linewidth=0.6, alpha=0.35)
    grid, low, middle, high = lines
    seeds = sum(1 for _, (told, _) in curves if len(told))
    axis.fill_between(grid, low, high, step='post', color=colour, alpha=0.2, linewidth=0)
    axis.step(grid, middle, where='post', color=colour, linewidth=2,
              label=None if label is None else f'{label}: median of {seeds} seeds')
