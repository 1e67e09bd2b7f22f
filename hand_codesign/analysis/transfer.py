"""
Table of designs measured in both physics engines (their transfer): a CSV and a Markdown.

Reads FOLDER/RUN-in-ENGINE.json, the `unseen.json` that `hand-codesign analyze BAG --unseen N
--engine ENGINE` writes, one per run and engine, and writes FOLDER.csv and FOLDER.md: per run,
the engine it was found in, its share of unseen worlds within the task's tolerance, median,
p90 and whether it found joint limits, in that engine and in the other one; then the mean
shares of each engine's runs (every run has the same number of worlds: the pooled shares).

--measures DIR (of `hand-codesign reproduce`, DIR/RUN.json, PyBullet) stands in for a run's
missing RUN-in-pybullet.json: its summary, measured on the same unseen worlds, is copied to
FOLDER/RUN-in-pybullet.json (small), so the table is then rewritten from FOLDER alone.

A run found in both engines (physics.engines, issue 47) is measured in both by one `analyze BAG
--unseen N`, whose unseen.json holds each engine's record: FOLDER/RUN-in-both.json. Its row is
found in "both"; "there" is PyBullet and "the other engine" MuJoCo.

Usage: hand-codesign transfer FOLDER --title TEXT [--note TEXT] [--measures DIR ...]
"""

import csv
import json
import pathlib

from hand_codesign.errors import UserError

ENGINES = ('pybullet', 'mujoco')
BOTH = 'both'  # a run found in both engines (physics.engines)
NAMES = {'pybullet': 'PyBullet', 'mujoco': 'MuJoCo', BOTH: 'both'}
COLUMNS = ['run', 'found_in', 'worlds', 'tolerance', 'within_found', 'within_other',
           'median_found', 'median_other', 'p90_found', 'p90_other', 'joint_limits_found',
           'joint_limits_other']


def copy_measures(folder, directories):
    """Write RUN-in-pybullet.json from DIR/RUN.json for the runs that have only MuJoCo's."""
    for directory in directories:
        for path in sorted(pathlib.Path(directory).glob('*.json')):
            run = path.stem
            target = folder / f'{run}-in-pybullet.json'
            if not (folder / f'{run}-in-mujoco.json').exists() or target.exists():
                continue
            measured = json.loads(path.read_text())
            target.write_text(json.dumps({
                'bag': measured['bag'], 'seed': measured['seed'], 'engine': 'pybullet',
                'run_engine': 'pybullet', 'unseen_worlds': measured['unseen_worlds'],
                'summaries': [measured['summary']], 'source': str(path)}, indent=1) + '\n')


def read_runs(folder):
    """Return {run: {engine: unseen.json}} of the folder."""
    runs = {}
    for path in sorted(folder.glob('*-in-*.json')):
        run, engine = path.stem.rsplit('-in-', 1)
        measured = json.loads(path.read_text())
        if engine == BOTH and set(measured.get('engines', ())) == set(ENGINES):
            runs.setdefault(run, {}).update(measured['engines'])
            continue
        if engine not in ENGINES:
            raise UserError(f'{path}: expected RUN-in-pybullet.json, RUN-in-mujoco.json or '
                            'RUN-in-both.json (of a run in both engines)')
        runs.setdefault(run, {})[engine] = measured
    return runs


def tolerance_text(tolerance):
    """Return '< 5 mm' style text of a summary's tolerance (plane, x, y, ...: m; else rad)."""
    if tolerance['kind'] == 'orientation':
        return f"{tolerance['kind']} < {tolerance['limit']:g} rad"
    return f"{tolerance['kind']} < {tolerance['limit'] * 1000:g} mm"


def value_text(value, tolerance):
    if tolerance['kind'] == 'orientation':
        return f'{value:.3f} rad'
    return f'{value * 1000:.1f} mm'


def runs_text(number):
    """Return "1 run" or "N runs"."""
    return '1 run' if number == 1 else f'{number} runs'


def rows_of(runs):
    """Return the table's rows (dicts of COLUMNS), a run measured in both engines each."""
    rows = []
    for run, measured in runs.items():
        if set(measured) != set(ENGINES):
            raise UserError(f'{run}: measured in {sorted(measured)} only, expected both')
        found = measured['mujoco']['run_engine']
        if found in ENGINES:
            other = 'mujoco' if found == 'pybullet' else 'pybullet'
            home, away = measured[found]['summaries'][0], measured[other]['summaries'][0]
        else:  # found in both: PyBullet "there", MuJoCo "in the other engine"
            found = BOTH
            home, away = (measured[engine]['summaries'][0] for engine in ENGINES)
        if home['worlds'] != away['worlds'] or home['tolerance'] != away['tolerance']:
            raise UserError(f'{run}: the two engines measured different worlds or tolerances')
        rows.append({'run': run, 'found_in': found, 'worlds': home['worlds'],
                     'tolerance': tolerance_text(home['tolerance']),
                     'within_found': home['within'], 'within_other': away['within'],
                     'median_found': home['median'], 'median_other': away['median'],
                     'p90_found': home['p90'], 'p90_other': away['p90'],
                     'joint_limits_found': home['joint_limits_found'],
                     'joint_limits_other': away['joint_limits_found'],
                     '_tolerance': home['tolerance']})
    return sorted(rows, key=lambda row: ((*ENGINES, BOTH).index(row['found_in']), row['run']))


def markdown(rows, title, note):
    """Return the Markdown table of the rows, with the mean shares of each engine's runs."""
    lines = [f'# {title}', '']
    if note:
        lines += [note, '']
    lines += ['| run | found in | within, there | within, in the other engine | median, there '
              '| median, other | p90, there | p90, other | joint limits found, there / other |',
              '|---|---|---|---|---|---|---|---|---|']
    for row in rows:
        tolerance = row['_tolerance']
        lines.append(
            f"| {row['run']} | {NAMES[row['found_in']]} | {row['within_found']:.0%} | "
            f"{row['within_other']:.0%} | {value_text(row['median_found'], tolerance)} | "
            f"{value_text(row['median_other'], tolerance)} | "
            f"{value_text(row['p90_found'], tolerance)} | "
            f"{value_text(row['p90_other'], tolerance)} | "
            f"{'yes' if row['joint_limits_found'] else 'no'} / "
            f"{'yes' if row['joint_limits_other'] else 'no'} |")
    for engine in (*ENGINES, BOTH):
        group = [row for row in rows if row['found_in'] == engine]
        if group:
            home = sum(row['within_found'] for row in group) / len(group)
            away = sum(row['within_other'] for row in group) / len(group)
            lines.append(f'| pooled, {runs_text(len(group))} | {NAMES[engine]} | {home:.0%} | '
                         f'{away:.0%} | | | | | |')
    tolerances = sorted({row['tolerance'] for row in rows})
    lines += ['', f"Within: the share of each run's {rows[0]['worlds']} unseen worlds that end "
              f"with {' / '.join(tolerances)}; \"there\": in the engine the run was found in"
              + (' (found in both: there is PyBullet, the other engine MuJoCo).'
                 if any(row['found_in'] == BOTH for row in rows) else '.'), '']
    return '\n'.join(lines)


def transfer_command(arguments):
    """
    Write FOLDER.csv and FOLDER.md of the runs measured in both engines; print where.

    Args:
        arguments: folder (of RUN-in-ENGINE.json), title and note (of the Markdown),
            measures (reproduce's measures/ folders standing in for missing PyBullet files).

    Returns:
        0; a folder without a run measured in both engines raises UserError (one line).
    """
    folder = pathlib.Path(arguments.folder)
    if not folder.is_dir():
        raise UserError(f'{folder}: not a folder of RUN-in-ENGINE.json files')
    copy_measures(folder, arguments.measures)
    rows = rows_of(read_runs(folder))
    if not rows:
        raise UserError(f'{folder}: no RUN-in-ENGINE.json files')
    with open(folder.with_suffix('.csv'), 'w', newline='') as stream:
        writer = csv.DictWriter(stream, COLUMNS, extrasaction='ignore')
        writer.writeheader()
        writer.writerows(rows)
    folder.with_suffix('.md').write_text(markdown(rows, arguments.title, arguments.note))
    print(f'wrote {folder.with_suffix(".csv")} and {folder.with_suffix(".md")} '
          f'({runs_text(len(rows))})')
    return 0
