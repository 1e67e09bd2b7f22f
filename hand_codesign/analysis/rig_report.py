"""
Prediction against measurement: the gap per objective of designs evaluated both ways.

A candidate has a prediction when a simulation evaluator answered it OK and a measurement when
a rig evaluator did (Evaluation.measured); `hand-codesign evaluate BAG --rig` records both,
and `hand-codesign analyze` adds this comparison to its report: a table (`rig_gap.csv`, a
section of report.md) and a plot of the gap, measured minus predicted, per objective.
"""

from dataclasses import dataclass
import pathlib
from typing import List

from hand_codesign.analysis.records import objective_names_of
from hand_codesign.core.contract import STATUS_OK
import numpy as np


@dataclass
class RigComparison:
    """The designs with both answers: their predicted and measured objectives."""

    objective_names: List[str]
    candidate_ids: np.ndarray
    predicted: np.ndarray   # (designs, objectives)
    measured: np.ndarray

    @property
    def gap(self):
        """Return measured minus predicted, per design and objective."""
        return self.measured - self.predicted

    def rows(self):
        """Return [(objective, mean predicted, mean measured, mean gap, largest |gap|)]."""
        gap = self.gap
        return [(name, float(self.predicted[:, index].mean()),
                 float(self.measured[:, index].mean()), float(gap[:, index].mean()),
                 float(np.abs(gap[:, index]).max()))
                for index, name in enumerate(self.objective_names)]

    def text(self):
        """Return the comparison as a plain-text table."""
        lines = [f'prediction (simulation) against measurement (rig), {len(self.candidate_ids)} '
                 'designs:',
                 f'{"objective":<16}{"predicted":>13}{"measured":>13}{"mean gap":>13}'
                 f'{"max |gap|":>13}']
        lines += [f'{name:<16}{predicted:>13.6g}{measured:>13.6g}{gap:>13.3g}{worst:>13.3g}'
                  for name, predicted, measured, gap, worst in self.rows()]
        return '\n'.join(lines)

    def markdown(self, figure_name=None):
        """Return the report.md section."""
        lines = ['', '## Prediction and measurement', '',
                 f'{len(self.candidate_ids)} designs were evaluated both in simulation and on a '
                 'rig (gap = measured - predicted, means over the designs).', '',
                 '| objective | predicted | measured | mean gap | max abs gap |',
                 '|---|---|---|---|---|']
        lines += [f'| {name} | {predicted:.6g} | {measured:.6g} | {gap:.3g} | {worst:.3g} |'
                  for name, predicted, measured, gap, worst in self.rows()]
        if figure_name:
            lines += ['', f'![{figure_name}]({figure_name})']
        return lines

    def write_csv(self, path):
        """Write one row per design and objective: predicted, measured, gap."""
        lines = ['candidate_id,objective,predicted,measured,gap']
        for row, candidate_id in enumerate(self.candidate_ids.tolist()):
            for index, name in enumerate(self.objective_names):
                lines.append(f'{candidate_id},{name},{self.predicted[row, index]!r},'
                             f'{self.measured[row, index]!r},{self.gap[row, index]!r}')
        pathlib.Path(path).write_text('\n'.join(lines) + '\n', encoding='utf-8')

    def plot(self, path, pyplot):
        """Plot the gap of each design per objective; return the path."""
        figure, axes = pyplot.subplots(figsize=(max(4.0, 0.9 * len(self.objective_names) + 2),
                                                3.4))
        positions = np.arange(len(self.objective_names))
        for row, candidate_id in enumerate(self.candidate_ids.tolist()):
            axes.scatter(positions, self.gap[row], s=18, label=f'candidate {candidate_id}')
        axes.axhline(0.0, color='grey', linewidth=0.8)
        axes.set_xticks(positions, self.objective_names, rotation=30, fontsize='small')
        axes.set_ylabel('measured - predicted')
        axes.set_title('gap between prediction and measurement', fontsize='medium')
        axes.grid(True, alpha=0.3)
        if len(self.candidate_ids) <= 10:
            axes.legend(fontsize='x-small')
        figure.tight_layout()
        figure.savefig(path, dpi=100)
        pyplot.close(figure)
        return pathlib.Path(path)


def rig_comparison(record):
    """Return the RigComparison of a RunRecord, or None when no design has both answers."""
    evaluations = record.evaluations
    if not len(evaluations) or 'measured' not in evaluations:
        return None
    names = objective_names_of(record)
    ok = np.asarray(evaluations['status']) == STATUS_OK
    measured = np.asarray(evaluations['measured'], dtype=bool)
    ids = np.asarray(evaluations['candidate_id'], dtype=np.uint64)
    first = {}   # (candidate id, measured) -> first OK row
    for row in np.flatnonzero(ok):
        first.setdefault((int(ids[row]), bool(measured[row])), row)
    both = sorted(candidate for candidate, kind in first if kind and (candidate, False) in first)
    if not both:
        return None

    def objectives(kind):
        return np.array([np.asarray(evaluations['objectives'][first[(candidate, kind)]],
                                    dtype=float)[:len(names)] for candidate in both])

    return RigComparison(list(names), np.array(both, dtype=np.uint64), objectives(False),
                         objectives(True))
