"""
Where a run's best design leaves the object on the plane, against where the world put it.

    hand-codesign offsets BAG [BAG ...] [--unseen 1000] [--training] [--table OUT]

Each bag's best design is simulated on N unseen worlds (core.experiments.measures, as `reproduce`
and `analyze --unseen` measure it). Per axis of the plane, x and y of the world, it prints the
share of worlds whose final offset from the last position goal is below 5 mm, and the
least-squares slope and the correlation of the object's final position on the world's start
offset along that axis. A slope near 1 with a high correlation says that the hand leaves the
object where the world put it along that axis: a part of the error no design of that hand
removes, since the hand cannot tell where the world put it.

--training also simulates the design on the worlds its run trained on (core.sim.worlds, the
run's seed and count), whole motions as the unseen ones: a share as low there as on unseen
worlds says the design falls short on the very worlds it was optimized on, not by
generalizing. --table OUT writes OUT.csv and OUT.md, a row per bag and set of worlds.
"""

import csv
import pathlib

from hand_codesign.analysis.records import final_design
from hand_codesign.core.experiments.measures import measure_worlds, unseen_world_states
from hand_codesign.core.sim.worlds import world_states
import numpy as np

TOLERANCE = 0.005  # m
COLUMNS = ['run', 'seed', 'worlds', 'count', 'within_plane', 'within_x', 'within_y',
           'median_plane_mm', 'p90_plane_mm', 'slope_y', 'correlation_y']


def axis_rows(measures, worlds):
    """Return [(axis, share within, slope, correlation)] of the plane's two axes."""
    rows = []
    for index, axis in enumerate('xy'):
        start = np.array([world.position_delta[index] for world in worlds])
        final = measures.final_positions[:, index]
        slope = np.polyfit(start, final, 1)[0]
        correlation = np.corrcoef(start, final)[0, 1]
        within = np.mean(measures.errors[axis] < TOLERANCE)
        rows.append((axis, float(within), float(slope), float(correlation)))
    return rows


def table_row(bag, task, kind, measures, axes):
    """Return the table's row (dict of COLUMNS) of one design on one set of worlds."""
    plane = measures.errors['plane']
    (_, within_x, _, _), (_, within_y, slope_y, correlation_y) = axes
    return {'run': pathlib.Path(bag).name, 'seed': task.seed, 'worlds': kind,
            'count': len(plane), 'within_plane': float(np.mean(plane < TOLERANCE)),
            'within_x': within_x, 'within_y': within_y,
            'median_plane_mm': 1000 * float(np.median(plane)),
            'p90_plane_mm': 1000 * float(np.percentile(plane, 90)),
            'slope_y': slope_y, 'correlation_y': correlation_y}


def write_table(out, rows):
    """Write OUT.csv and OUT.md of the rows."""
    out = pathlib.Path(out)
    with out.with_suffix('.csv').open('w', newline='') as stream:
        writer = csv.DictWriter(stream, COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    lines = ['| run | seed | worlds | within 5 mm in the plane | along x | along y | median '
             "(plane) | p90 (plane) | final y on the start's y: slope, correlation |",
             '|---|---|---|---|---|---|---|---|---|']
    lines += [f"| {row['run']} | {row['seed']} | {row['worlds']}, {row['count']} | "
              f"{row['within_plane']:.0%} | {row['within_x']:.0%} | {row['within_y']:.0%} | "
              f"{row['median_plane_mm']:.1f} mm | {row['p90_plane_mm']:.1f} mm | "
              f"{row['slope_y']:.2f}, {row['correlation_y']:.2f} |"
              for row in rows]
    out.with_suffix('.md').write_text('\n'.join(lines) + '\n')
    print(f'wrote {out.with_suffix(".csv")} and {out.with_suffix(".md")}')


def report(bag, task, kind, row, axes):
    """Print the shares of one design on one set of worlds (its table row and axis rows)."""
    print(f"{bag}: seed {task.seed}, {row['count']} {kind} worlds; within 5 mm in the "
          f"plane {100 * row['within_plane']:.1f} %")
    for axis, within, slope, correlation in axes:
        print(f'  along {axis}: within 5 mm {100 * within:.1f} %; final position on the '
              f"start's offset: slope {slope:.2f}, correlation {correlation:.2f}")


def offsets_command(arguments):
    """
    Measure each bag's best design and print (and with --table write) its shares by axis.

    Args:
        arguments: bags (paths of finished runs), unseen (how many unseen worlds), training
            (also the run's own worlds), table (OUT of OUT.csv and OUT.md, or None).

    Returns:
        0; a path that is no bag of the recorder raises UserError (one line).
    """
    rows = []
    for bag in arguments.bags:
        task, x, _ = final_design(bag)
        sets = [('unseen', unseen_world_states(task, arguments.unseen))]
        if arguments.training:
            sets.insert(0, ('training', world_states(task)))
        for kind, worlds in sets:
            measures = measure_worlds(x, task, worlds)
            axes = axis_rows(measures, worlds)
            rows.append(table_row(bag, task, kind, measures, axes))
            report(bag, task, kind, rows[-1], axes)
    if arguments.table:
        write_table(arguments.table, rows)
    return 0
