"""
A campaign's figures, legible from two configurations to thirty.

- Errors: a box per configuration for the start and the end of the motion, configurations
  down the page (one row each, their names in full beside them), a panel per error kind: the
  figure grows in height with the configurations, not into a strip thousands of pixels wide.
- Convergence: up to ten configurations share one axis, one colour each (matplotlib's ten
  distinguishable ones); more get small multiples, a panel per configuration on the same
  axes, that configuration's median and band in colour over every other configuration's
  median in light grey, so each is read on its own and against the field.

The file's suffix (.png, .svg, .pdf) is its format.
"""

import numpy as np

SHARED_AXIS_MOST = 10     # configurations one axis shows apart by colour
COLUMNS = 5               # panels per row of the small multiples
ROW_INCHES = 0.32         # height of a configuration's row in the errors figure


def pyplot_module():
    """Return pyplot on the Agg backend (no display needed); matplotlib loads only here."""
    import matplotlib
    matplotlib.use('Agg')
    from matplotlib import pyplot
    return pyplot


def plot_errors(path, groups, tolerance, title, kinds=None):
    """
    Box plots of the pooled initial and final errors per group [(label, record list)].

    One panel per error kind (default: the tolerance's), configurations down the page, the
    tolerance a dashed line. Boxes p25-p75, whiskers p5-p95, over the unseen worlds of every
    seed.
    """
    pyplot = pyplot_module()
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


def plot_convergence(path, panels, title, band):
    """
    Best fitness so far against evaluations, per configuration across its seeds.

    panels: [(label, [(seed, (evaluations told, best so far))])]; band: a function of such
    curves returning (evaluations, p25, median, p75) (campaign.seed_band). One shared axis
    for up to SHARED_AXIS_MOST configurations, small multiples beyond.
    """
    pyplot = pyplot_module()
    bands = [band(curves) for _, curves in panels]
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
