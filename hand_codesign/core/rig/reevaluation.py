"""
Re-evaluating recorded designs: prediction and measurement of the same candidates.

`hand-codesign evaluate BAG --rig` sends a run's best designs once more, to any evaluator: a
simulation evaluator answers with the prediction, a rig evaluator (Evaluation.measured) with
the measurement, and the new bag holds both side by side. A `Plan` is what to send (the
run's RunInfo fields under a new run id and the candidates, genomes exact); `AnswerBook`
says when every candidate has both answers (a rejection counts as an answer: a trial that
lost tracking is not retried by itself).
"""

from dataclasses import dataclass
import json
from typing import Tuple

from hand_codesign.core.task.variant import Variant
import numpy as np

RUN_FIELDS = ('run_id', 'task_name', 'task_yaml', 'seed', 'algorithm', 'iterations',
              'population', 'world_states', 'objective_names', 'versions', 'resumed_from',
              'engine', 'engine_version')


@dataclass(frozen=True)
class PlannedCandidate:
    """One design to re-evaluate, as the optimizer sent it (the fields candidate_message reads)."""

    candidate_id: int
    generation: int
    structure: Tuple[int, ...]
    world_states: int
    horizon: float
    x: Tuple[float, ...]
    genome_names: Tuple[str, ...]

    @property
    def variant(self):
        """Return the Variant of the run's task it was evaluated on (as its plan records it)."""
        return Variant(structure=tuple(self.structure), world_states=int(self.world_states),
                       horizon=float(self.horizon))


def plan_text(run, designs, suffix='rig'):
    """Return the JSON text of a plan: a RunInfo-like `run` (new id) and RecordedDesigns."""
    fields = {name: getattr(run, name) for name in RUN_FIELDS}
    fields['objective_names'] = list(fields['objective_names'])
    fields['versions'] = list(fields['versions'])
    fields['resumed_from'] = run.run_id
    fields['run_id'] = f'{run.run_id}-{suffix}'
    candidates = [{'candidate_id': int(design.candidate_id),
                   'generation': int(design.generation),
                   'structure': [int(joints) for joints in design.structure],
                   'world_states': int(design.world_states), 'horizon': float(design.horizon),
                   'x': np.asarray(design.x, dtype=float).tolist(),   # repr: exact floats
                   'genome_names': list(design.genome_names)} for design in designs]
    return json.dumps({'run': fields, 'candidates': candidates}, indent=1)


def read_plan(text):
    """Return (run fields, [PlannedCandidate]) of a plan's JSON text; ValueError if malformed."""
    try:
        plan = json.loads(text)
        candidates = [PlannedCandidate(
            candidate_id=int(entry['candidate_id']), generation=int(entry['generation']),
            structure=tuple(entry['structure']), world_states=int(entry['world_states']),
            horizon=float(entry['horizon']), x=tuple(float(v) for v in entry['x']),
            genome_names=tuple(entry['genome_names'])) for entry in plan['candidates']]
        return {name: plan['run'][name] for name in RUN_FIELDS}, candidates
    except (ValueError, KeyError, TypeError) as error:
        raise ValueError(f'not a re-evaluation plan: {type(error).__name__}: {error}') from None


class AnswerBook:
    """Which planned candidates still lack a simulated or a measured answer."""

    def __init__(self, candidate_ids):
        self.missing = {int(candidate_id): {False, True} for candidate_id in candidate_ids}

    def answered(self, candidate_id, measured):
        """Take an Evaluation (any status) of a candidate: measured or simulated."""
        self.missing.get(int(candidate_id), set()).discard(bool(measured))

    @property
    def done(self):
        """Return True once every candidate has both answers."""
        return not any(self.missing.values())

    def describe(self):
        """Return a line naming what is still missing."""
        lacking = [f'{candidate_id} (' + ' and '.join('measured' if kind else 'simulated'
                                                      for kind in sorted(kinds)) + ')'
                   for candidate_id, kinds in sorted(self.missing.items()) if kinds]
        return 'still missing: ' + ', '.join(lacking) if lacking else 'complete'
