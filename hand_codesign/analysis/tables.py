"""Tables of a run's report: CSV files whose numbers read back bit for bit, and Markdown."""

import numpy as np


def number_text(value):
    """Return the exact text of a float for CSV ('' for NaN)."""
    return '' if value != value else repr(value)


def float_texts(column):
    """Return the exact texts of a float column."""
    return [number_text(value) for value in np.asarray(column, dtype=float).tolist()]


def int_texts(column):
    return [str(value) for value in np.asarray(column).tolist()]


def bool_texts(column):
    return ['true' if value else 'false' for value in np.asarray(column, dtype=bool).tolist()]


def _csv_text(value):
    text = str(value)
    if any(mark in text for mark in ',"\n\r'):
        text = '"' + text.replace('"', '""') + '"'
    return text


def write_csv(path, header, columns):
    """Write columns (lists of texts, equal lengths) under header as CSV."""
    with open(path, 'w', encoding='utf-8', newline='') as stream:
        stream.write(','.join(_csv_text(name) for name in header) + '\n')
        stream.writelines(','.join(row) + '\n' for row in zip(*columns))


def write_evaluations_csv(path, rows):
    """Write EvaluationRows as the evaluations CSV."""
    header = (['generation', 'candidate_id', 'evaluator', 'status']
              + list(rows.objective_names)
              + ['fitness', 'collision', 'unstable_worlds', 'simulated_time', 'wall_time',
                 'reason'] + list(rows.gene_names))
    columns = [int_texts(rows.generation), int_texts(rows.candidate_id),
               [_csv_text(value) for value in rows.evaluator_id.tolist()],
               list(rows.status)]
    rejected = rows.status == 'rejected'
    for index in range(len(rows.objective_names)):
        columns.append(float_texts(rows.objectives[:, index]))
    fitness = np.where(rejected, np.nan, rows.fitness)
    columns += [float_texts(fitness), bool_texts(rows.collision),
                int_texts(rows.unstable_worlds), float_texts(rows.simulated_time),
                float_texts(rows.wall_time),
                [_csv_text(value) for value in rows.reason.tolist()]]
    for index in range(len(rows.gene_names)):
        columns.append(float_texts(rows.genes[:, index]))
    write_csv(path, header, columns)


def aligned_table(table):
    """Return rows of text cells as lines, each column right-aligned to its widest cell."""
    widths = [max(len(row[column]) for row in table) for column in range(len(table[0]))]
    return '\n'.join('  '.join(cell.rjust(width) for cell, width in zip(row, widths)).rstrip()
                     for row in table)


def markdown_cell(text):
    return str(text).replace('|', '\\|').replace('\n', ' ')


# -------------------------------------------------------------------- figures


def percent(share):
    """Return a share as the tables write it, e.g. '58 %'."""
    return f'{100 * share:.0f} %'


def error_text(value, tolerance):
    """Return an error in the table's unit: mm for distances, rad for angles, x for poses."""
    if tolerance.kind == 'orientation':
        return f'{value:.3f} rad'
    if tolerance.kind == 'pose':
        return f'{value:.2f} x'
    return f'{value * 1000:.1f} mm'
