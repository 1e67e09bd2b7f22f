"""
`hand-codesign robustness BAG [--samples N] [--out DIR] [--workers P]`: Fig. 3 for a run.

Evaluates the run's best design on many world states with `core.experiments.robustness` on P
processes (default: every core) and writes into DIR (default `<bag>_robustness` next to the bag):

- `worlds.csv`: one row per world: its randomized values, the object's position (m) and
  orientation (rad) error with respect to the last goal at the start and at the end,
  whether the design started in collision there, and the poses the errors come from, in world
  coordinates: the object's start (`start_position_x` .. `start_orientation_w`), the last goal
  of that world (`goal_...`) and the object's final pose (`final_position_x`, `_y`, `_z` in m,
  `final_orientation_x` .. `_w` a quaternion);
- `percentiles.csv` and the printed table: percentiles of the four errors;
- `robustness.png`: the paper's Fig. 3 for this design: the distribution of the initial and
  the final errors, as a scatter of position against orientation error and as box plots.

For a hierarchy run (Fig. 3 per structure), every structure the run checked has its best design
(the better of its optimizations, as the search replayed from the bag finds it) evaluated on
the same worlds: DIR gets one folder per structure (`structure_1_3/` with worlds.csv and
percentiles.csv), `structures.csv` (per structure the median, p95 and mean of the four errors)
and `structures.png`, the initial and final error distributions of every structure side by
side.

World states: when N is v ** k for the k quantities the task randomizes (default 15,625 =
5 ** 6, the paper's), the grid of v evenly spaced values per quantity, all combinations
(`core.sim.worlds.grid_world_states`); otherwise N worlds drawn uniformly from the task's ranges
with a seed derived from the run's seed (other worlds than those the run optimized on).
"""

import os
import pathlib
import time

from hand_codesign.analysis import records
from hand_codesign.analysis.tables import write_csv
from hand_codesign.core.experiments.robustness import evaluate_robustness
from hand_codesign.core.sim.worlds import grid_world_states
from hand_codesign.core.sim.worlds import randomized_quantities
from hand_codesign.core.sim.worlds import world_states
from hand_codesign.core.task.variant import Variant
from hand_codesign.errors import UserError
from hand_codesign.outputs import staged
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
    out = (pathlib.Path(arguments.out) if arguments.out
           else default_output_dir(record.path))
    bests = records.structure_bests(record)
    if bests:
        return structures_command(record, bests, arguments.samples, workers, out)
    design = records.recorded_design(record, records.best_candidate_id(record))
    task = records.run_task_of(record, Variant(structure=tuple(design.structure)))
    worlds, how = robustness_worlds(task, arguments.samples)
    print(f'evaluating candidate {design.candidate_id} (generation {design.generation}, '
          f'structure {list(design.structure)}) on {len(worlds)} world states ({how}) with '
          f'{workers} processes')
    report = timed_robustness(design.x, task, worlds, workers)
    with staged(out) as folder:
        paths = write_report(folder, report, f'{task.name}, candidate {design.candidate_id}')
    print(percentile_table(report))
    print(f'collisions at the start: {int(np.sum(report.collisions))} of {report.size} '
          'worlds')
    print(f'robustness: {out} ({", ".join(path.name for path in paths)})')
    return 0


def timed_robustness(x, task, worlds, workers):
    """Evaluate one design on the worlds with `workers` processes; print the rate."""
    started = time.perf_counter()
    report = evaluate_robustness(x, task, worlds=worlds, processes=workers,
                                 chunk_size=chunk_size(len(worlds), workers))
    seconds = time.perf_counter() - started
    print(f'{len(worlds)} worlds in {seconds:.1f} s ({len(worlds) / seconds:.1f} worlds/s)')
    return report


def structures_command(record, bests, samples, workers, out):
    """Fig. 3 per structure: each structure's best design on the same worlds, side by side."""
    reports = []
    for structure, candidate_id in bests:
        design = records.recorded_design(record, candidate_id)
        task = records.run_task_of(record, Variant(structure=tuple(structure)))
        worlds, how = robustness_worlds(task, samples)
        print(f'structure {list(structure)}: evaluating its best design, candidate '
              f'{candidate_id}, on {len(worlds)} world states ({how}) with {workers} processes')
        report = timed_robustness(design.x, task, worlds, workers)
        reports.append((structure, candidate_id, report))
        print(percentile_table(report))
    with staged(out) as staging:
        for structure, _, report in reports:
            write_tables(staging / ('structure_' + '_'.join(str(joints) for joints in structure)),
                         report)
        summary_path = out / 'structures.csv'
        write_structures_csv(staging / summary_path.name, reports)
        figure_path = out / 'structures.png'
        plot_structures(staging / figure_path.name, reports,
                        f'{task.name}, {len(worlds)} world states')
    print(f'robustness of {len(reports)} structures: {out} ({summary_path.name}, '
          f'{figure_path.name}, one folder per structure)')
    return 0


def write_structures_csv(path, reports):
    """Write per structure and error the median, p95 and mean (SI units)."""
    header = ['structure', 'candidate_id', 'error', 'unit', 'p50', 'p95', 'mean']
    rows = []
    for structure, candidate_id, report in reports:
        for when, quantity, unit, values in percentile_rows(report):
            rows.append([' '.join(str(joints) for joints in structure), str(candidate_id),
                         f'{when}_{quantity}', unit,
                         repr(float(values[PERCENTILES.index(50)])),
                         repr(float(values[PERCENTILES.index(95)])), repr(float(values[-2]))])
    write_csv(path, header, [list(column) for column in zip(*rows)])


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
    paths = write_tables(out, report)
    figure_path = out / 'robustness.png'
    plot_robustness(figure_path, report, title)
    return paths + [figure_path]


def write_tables(out, report):
    """Write worlds.csv and percentiles.csv into out; return their paths."""
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
    return [worlds_path, percentiles_path]


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


def plot_structures(path, reports, title):
    """Plot Fig. 3 per structure: initial and final error box plots side by side (mm, deg)."""
    import matplotlib
    matplotlib.use('Agg')
    from matplotlib import pyplot
    figure, axes = pyplot.subplots(2, 1, figsize=(max(6.0, 1.3 * len(reports) + 2), 7.5),
                                   sharex=True)
    positions = np.arange(len(reports)) * 3.0
    names = [str(list(structure)) for structure, _, _ in reports]
    for ax, column, scale, label in ((axes[0], 0, 1000.0, 'position error (mm)'),
                                     (axes[1], 1, 180.0 / np.pi, 'orientation error (deg)')):
        for offset, when, colour in ((0.0, 'initial', 'tab:grey'), (1.0, 'final', 'tab:blue')):
            data = [(report.initial_errors if when == 'initial' else report.final_errors)[
                :, column] * scale for _, _, report in reports]
            boxes = ax.boxplot(data, positions=positions + offset, widths=0.8,
                               whis=(5, 95), showfliers=False, patch_artist=True)
            for box in boxes['boxes']:
                box.set_facecolor(colour)
                box.set_alpha(0.6)
            ax.plot([], [], color=colour, linewidth=6, alpha=0.6, label=when)
        ax.set_ylabel(label)
        ax.grid(True, axis='y', alpha=0.3)
    axes[0].legend(fontsize='small')
    axes[1].set_xticks(positions + 0.5, names)
    axes[1].set_xlabel('structure (joints per finger); box: p25-p75, whiskers: p5-p95')
    figure.suptitle(f'robustness per structure: {title}', fontsize='medium')
    figure.tight_layout()
    figure.savefig(path, dpi=100)
    pyplot.close(figure)
