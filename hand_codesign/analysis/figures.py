"""Figures of a run's report: convergence, archive heat map, Pareto fronts (matplotlib)."""

import pathlib

import numpy as np


def load_pyplot():
    import matplotlib
    matplotlib.use('Agg')
    from matplotlib import pyplot
    return pyplot


def _scale(axes, values):
    finite = values[np.isfinite(values)]
    if len(finite) and finite.min() > 0 and finite.max() > 20 * finite.min():
        axes.set_yscale('log')


def plot_convergence(path, generations, names, title, restarts=()):
    """
    Plot best and median of each objective per generation, and the best fitness so far.

    restarts: core.search.restarts Restart records; each restart is a dashed line at its
    generation.
    """
    pyplot = load_pyplot()
    panels = len(names) + 1
    columns = min(panels, 3)
    rows = -(-panels // columns)
    figure, axes = pyplot.subplots(rows, columns, figsize=(4.2 * columns, 3.2 * rows),
                                   squeeze=False)
    x = np.arange(len(generations))
    changes = [index for index in range(1, len(generations))
               if generations.structures[index] != generations.structures[index - 1]]
    for index, name in enumerate(names + ['fitness of the best design so far']):
        ax = axes.flat[index]
        if index < len(names):
            ax.plot(x, generations.best[:, index], label='best', color='tab:blue')
            ax.plot(x, generations.median[:, index], label='median', color='tab:orange')
            _scale(ax, np.concatenate([generations.best[:, index],
                                       generations.median[:, index]]))
            ax.legend(fontsize='small')
        else:
            ax.plot(x, generations.best_fitness, color='tab:green')
            _scale(ax, generations.best_fitness)
        if ax.get_yscale() == 'linear':
            ax.ticklabel_format(axis='y', useOffset=False)
        for change in changes:
            ax.axvline(change - 0.5, color='grey', linestyle=':', linewidth=0.8)
        for restart in restarts[1:]:
            ax.axvline(restart.generation - 0.5, color='tab:red', linestyle='--',
                       linewidth=0.8)
        if changes:
            for start in [0] + changes:
                ax.text(start - 0.4, 0.98, 'x'.join(map(str, generations.structures[start])),
                        transform=ax.get_xaxis_transform(), fontsize='x-small',
                        verticalalignment='top', color='dimgrey')
        ax.set_title(name, fontsize='medium')
        ax.xaxis.get_major_locator().set_params(integer=True)
        ax.set_xlabel('generation' + (' (all structures)' if changes else ''))
        ax.grid(True, alpha=0.3)
    for ax in list(axes.flat)[panels:]:
        ax.axis('off')
    figure.suptitle(f'convergence of {title}' if title else 'convergence', fontsize='medium')
    figure.tight_layout()
    figure.savefig(path, dpi=100)
    pyplot.close(figure)
    return pathlib.Path(path)


def plot_archive(path, archive, title):
    """Plot a quality-diversity archive: its grid over two descriptors, colour = fitness."""
    pyplot = load_pyplot()
    grid = archive.fitness_grid()
    names, units = archive.describe.names, archive.describe.units
    (x_low, x_high), (y_low, y_high) = archive.ranges
    figure, ax = pyplot.subplots(figsize=(6.4, 5.0))
    # a cell's fitness is its elite's weighted sum (lower is better): the best cells darkest.
    # Cells far above the others (a start collision costs 10,000 per objective) would flatten
    # the scale: above 10 times the median cell they are drawn grey, off the scale.
    shown = np.ma.masked_invalid(grid.T)
    values = grid[np.isfinite(grid)]
    ceiling = 10.0 * abs(float(np.median(values)))
    within = values[values <= ceiling]
    colormap = pyplot.get_cmap('viridis').with_extremes(over='lightgrey')
    image = ax.pcolormesh(np.linspace(x_low, x_high, archive.cells[0] + 1),
                          np.linspace(y_low, y_high, archive.cells[1] + 1), shown,
                          cmap=colormap, shading='flat',
                          vmax=float(within.max()) if len(within) else None)
    over = len(values) - len(within)
    best = archive.result
    # the result is its cell's elite; its descriptors may be outcomes, not in the genome
    point = next((elite.descriptors for elite in archive.elites()
                  if best is not None and elite.candidate_id == best.candidate_id), None)
    if point is not None:
        ax.plot(point[0], point[1], marker='*', markersize=14, color='tab:red',
                markeredgecolor='white', linestyle='none',
                label=f'recommended: candidate {best.candidate_id} ({best.fitness:.4g})')
    if over:
        ax.fill_between([], [], color='lightgrey',
                        label=f'over 10 x the median cell ({over} cell{"s" if over > 1 else ""})')
    if point is not None or over:
        ax.legend(fontsize='small', loc='upper right')
    figure.colorbar(image, ax=ax, extend='max' if over else 'neither',
                    label='weighted sum of the objectives (lower is better)')
    ax.set_xlabel(f'{names[0]} ({units[0]})' if units[0] else names[0])
    ax.set_ylabel(f'{names[1]} ({units[1]})' if units[1] else names[1])
    filled = int(np.isfinite(grid).sum())
    ax.set_title(f'{archive.algorithm} archive of {title}: {filled} of {grid.size} cells',
                 fontsize='medium')
    figure.savefig(path, dpi=100)
    pyplot.close(figure)
    return pathlib.Path(path)


def plot_pareto(path, fronts, names):
    """Plot the Pareto front of every generation (colour = generation) for objective pairs."""
    pyplot = load_pyplot()
    pairs = [(i, j) for i in range(len(names)) for j in range(i + 1, len(names))][:6]
    if not pairs:
        pairs = [(0, 0)]
    columns = min(len(pairs), 3)
    rows = -(-len(pairs) // columns)
    figure, axes = pyplot.subplots(rows, columns, figsize=(4.6 * columns, 3.8 * rows),
                                   squeeze=False)
    colormap = pyplot.get_cmap('viridis')
    count = len(fronts)
    for ax, (i, j) in zip(axes.flat, pairs):
        for order, (_, generation, front) in enumerate(fronts):
            colour = colormap(order / max(count - 1, 1))
            ax.scatter(front[:, i], front[:, j], s=8, color=colour, alpha=0.6)
        last = fronts[-1][2]
        ordered = last[np.argsort(last[:, i])]
        ax.plot(ordered[:, i], ordered[:, j], 'o-', color='tab:red', markersize=3,
                linewidth=1, label=f'final front (generation {fronts[-1][1]})')
        ax.set_xlabel(names[i])
        ax.set_ylabel(names[j])
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize='small')
    for ax in list(axes.flat)[len(pairs):]:
        ax.axis('off')
    mappable = pyplot.cm.ScalarMappable(cmap=colormap)
    mappable.set_clim(fronts[0][0], max(fronts[-1][0], fronts[0][0] + 1))
    figure.colorbar(mappable, ax=list(axes.flat), label='generation (all structures, in order)')
    figure.suptitle('Pareto front per generation', fontsize='medium')
    figure.savefig(path, dpi=100)
    pyplot.close(figure)
    return pathlib.Path(path)
