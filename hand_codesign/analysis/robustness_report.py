"""
`hand-codesign robustness BAG [--samples N] [--out DIR] [--workers P]`: Fig. 3 for a run.

Evaluates the run's best design on many world states with `core.robustness` on P processes
(default: every core) and writes into DIR (default `<bag>_robustness` next to the bag):

- `worlds.csv`: one row per world: its randomized values, the object's position (m) and
  orientation (rad) error with respect to the last goal at the start and at the end,
  whether the design started in collision there, and the poses the errors come from, in world
  coordinates: the object's start (`start_position_x` .. `start_orientation_w`), the last goal
  of that world (`goal_...`) and the object's final pose (`final_position_x`, `_y`, `_z` in m,
  `final_orientation_x` .. `_w` a quaternion);
- `percentiles.csv` and the printed table: percentiles of the four errors;
- `robustness.png`: the paper's Fig. 3 for this design: the distribution of the initial and
  the final errors, as a scatter of position against orientation error and as box plots.

World states: when N is v ** k for the k quantities the task randomizes (default 15,625 =
5 ** 6, the paper's), the grid of v evenly spaced values per quantity, all combinations
(`core.worlds.grid_world_states`); otherwise N worlds drawn uniformly from the task's ranges
with a seed derived from the run's seed (other worlds than those the run optimized on).
"""

import os
import pathlib
import time

from hand_codesign.analysis import records
from hand_codesign.analysis.report import write_csv
from hand_codesign.core.robustness import evaluate_robustness
from hand_codesign.core.worlds import grid_world_states
from hand_codesign.core.worlds import randomized_quantities
from hand_codesign.core.worlds import world_states
from hand_codesign.errors import UserError
import numpy as np

PERCENTILES = (5, 25, 50, 75, 90, 95, 99)
# Random (not grid) robustness worlds are drawn with the run's seed plus this offset.
RANDOM_WORLDS_SEED_OFFSET = 1_000_003


def robustness_command(arguments):
    """Evaluate the best design of a bag on many worlds and write the Fig. 3 report."""
    if arguments.samples < 1:
        raise UserError(f'--samples: expected a positive number of world states, got '
                        f'{arguments.samples}')
    workers = arguments.workers or available_cores()
    if workers < 1:
        raise UserError(f'--workers: expected 1 or more processes, got {workers}')
    record = records.open_run(arguments.bag)
    design = records.recorded_design(record, records.best_candidate_id(record))
    task = records.run_task_of(record, design.structure or None)
    worlds, how = robustness_worlds(task, arguments.samples)
    out = (pathlib.Path(arguments.out) if arguments.out
           else default_output_dir(record.path))
    print(f'evaluating candidate {design.candidate_id} (generation {design.generation}, '
          f'structure {list(design.structure)}) on {len(worlds)} world states ({how}) with '
          f'{workers} processes')
    started = time.perf_counter()
    report = evaluate_robustness(design.x, task, worlds=worlds, processes=workers,
                                 chunk_size=chunk_size(len(worlds), workers))
    seconds = time.perf_counter() - started
    print(f'{len(worlds)} worlds in {seconds:.1f} s ({len(worlds) / seconds:.1f} worlds/s)')
    paths = write_report(out, report, f'{task.name}, candidate {design.candidate_id}')
    print(percentile_table(report))
    print(f'collisions at the start: {int(np.sum(report.collisions))} of {report.size} '
          'worlds')
    print(f'robustness: {out} ({", ".join(path.name for path in paths)})')
    return 0


def available_cores():
    """Return the cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def default_output_dir(bag_path):
    """Return `<bag>_robustness` next to the bag."""
    return records.beside_bag(bag_path, '_robustness')


def chunk_size(count, workers):
    """Return worlds per job: about four jobs per process, at most 125 worlds each."""
    return max(1, min(125, -(-count // (4 * workers))))


def robustness_worlds(task, samples):
    """Return (worlds, description): the grid when samples is v ** k, else seeded draws."""
    quantities = randomized_quantities(task)
    if not quantities:
        return grid_world_states(task, 1), 'the task randomizes nothing: its one world'
    values = round(samples ** (1.0 / len(quantities)))
    for candidate in (values - 1, values, values + 1):
        if candidate >= 2 and candidate ** len(quantities) == samples:
            return (grid_world_states(task, candidate),
                    f'grid of {candidate} values on each of {len(quantities)} randomized '
                    f'quantities: {", ".join(quantities)}')
    seeded = task.replace(seed=task.seed + RANDOM_WORLDS_SEED_OFFSET)
    return (world_states(seeded, count=samples),
            f'uniform in the ranges of the task, seed {seeded.seed}')


ERRORS = (('initial', 'position', 0), ('initial', 'orientation', 1),
          ('final', 'position', 0), ('final', 'orientation', 1))


def percentile_rows(report):
    """Return [(when, quantity, unit, [percentiles..., mean, max])] in SI units."""
    rows = []
    for when, quantity, column in ERRORS:
        errors = (report.initial_errors if when == 'initial' else report.final_errors)[:, column]
        values = list(np.percentile(errors, PERCENTILES))
        values += [float(np.mean(errors)), float(np.max(errors))]
        rows.append((when, quantity, 'm' if column == 0 else 'rad', values))
    return rows


def percentile_table(report):
    """Return the printed table: percentiles in mm and degrees."""
    header = ['error', 'unit'] + [f'p{p}' for p in PERCENTILES] + ['mean', 'max']
    table = [header]
    for when, quantity, _, values in percentile_rows(report):
        scale, unit = (1000.0, 'mm') if quantity == 'position' else (180.0 / np.pi, 'deg')
        table.append([f'{when} {quantity}', unit] + [f'{value * scale:.3g}' for value in values])
    widths = [max(len(row[index]) for row in table) for index in range(len(header))]
    return '\n'.join('  '.join(cell.rjust(width) if index > 1 else cell.ljust(width)
                               for index, (cell, width) in enumerate(zip(row, widths)))
                     for row in table)


def write_report(out, report, title):
    """Write worlds.csv, percentiles.csv and robustness.png into out; return their paths."""
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise UserError(f'--out {out}: cannot create the folder: {error}') from None
    worlds_path = out / 'worlds.csv'
    report.write_csv(worlds_path)
    percentiles_path = out / 'percentiles.csv'
    header = ['error', 'unit'] + [f'p{p}' for p in PERCENTILES] + ['mean', 'max']
    rows = percentile_rows(report)
    columns = [[f'{when}_{quantity}' for when, quantity, _, _ in rows],
               [unit for _, _, unit, _ in rows]]
    for index in range(len(header) - 2):
        columns.append([repr(float(values[index])) for *_, values in rows])
    write_csv(percentiles_path, header, columns)
    figure_path = out / 'robustness.png'
    plot_robustness(figure_path, report, title)
    return [worlds_path, percentiles_path, figure_path]


def plot_robustness(path, report, title):
    """Plot initial and final errors as in Fig. 3: scatter and box plots (mm, degrees)."""
    import matplotlib
    matplotlib.use('Agg')
    from matplotlib import pyplot
    millimetres = 1000.0
    degrees = 180.0 / np.pi
    figure, axes = pyplot.subplots(1, 3, figsize=(13.5, 4.2),
                                   gridspec_kw={'width_ratios': [1.4, 1, 1]})
    scatter = axes[0]
    size = 4 if report.size > 2000 else 10
    scatter.scatter(report.initial_errors[:, 0] * millimetres,
                    report.initial_errors[:, 1] * degrees, s=size, alpha=0.35,
                    color='tab:grey', label='initial', linewidths=0)
    scatter.scatter(report.final_errors[:, 0] * millimetres,
                    report.final_errors[:, 1] * degrees, s=size, alpha=0.5,
                    color='tab:blue', label='final', linewidths=0)
    if np.any(report.collisions):
        scatter.scatter(report.initial_errors[report.collisions, 0] * millimetres,
                        report.initial_errors[report.collisions, 1] * degrees, s=size * 2,
                        color='tab:red', marker='x', label='start in collision')
    scatter.set_xlabel('position error (mm)')
    scatter.set_ylabel('orientation error (deg)')
    scatter.legend(fontsize='small', markerscale=2)
    scatter.grid(True, alpha=0.3)
    for ax, column, scale, label in ((axes[1], 0, millimetres, 'position error (mm)'),
                                     (axes[2], 1, degrees, 'orientation error (deg)')):
        ax.boxplot([report.initial_errors[:, column] * scale,
                    report.final_errors[:, column] * scale],
                   whis=(5, 95), showfliers=False)
        ax.set_xticks([1, 2], ['initial', 'final'])
        ax.set_ylabel(label)
        ax.set_title('box: p25-p75, whiskers: p5-p95', fontsize='small')
        ax.grid(True, axis='y', alpha=0.3)
    figure.suptitle(f'robustness of {title} on {report.size} world states', fontsize='medium')
    figure.tight_layout()
    figure.savefig(path, dpi=100)
    pyplot.close(figure)
