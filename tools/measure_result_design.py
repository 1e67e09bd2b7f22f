"""
A reproduce campaign's committed design measured on its unseen worlds in one physics engine.

A campaign keeps each run's best design in `result-RUN.json` (key 'design': gene name ->
value) even when the run's bag is gone. This rebuilds the run's task from a pinned preset of
config/reproduce/ with the run's seed, encodes the design into its genome and measures it on
the same unseen worlds as `hand-codesign analyze BAG --unseen N --engine ENGINE` (the same
record, analysis.unseen.engine_report), written as FOLDER/RUN-in-ENGINE.json for
`hand-codesign transfer FOLDER`.

Usage: python tools/measure_result_design.py RESULT.json --preset task6_palm_beside.yaml
       --engine mujoco --out FOLDER [--unseen 1000] [--processes 1]   (from the repository's root)
"""

import argparse
import ast
import json
import pathlib

from hand_codesign.analysis.unseen import engine_report
from hand_codesign.core.run.runs import run_task
from hand_codesign.core.task.genome import genome_spec
from hand_codesign.core.task.variant import Variant

PRESETS = pathlib.Path(__file__).resolve().parents[1] / 'config' / 'reproduce'


def result_task_and_genome(result, preset, engine):
    """Return (task, normalized genome) of a campaign's result record on a preset."""
    design = result['design']
    if isinstance(design, str):  # written as the dict's repr
        design = ast.literal_eval(design)
    text = (PRESETS / preset).read_text()
    task = run_task(text, f'config/reproduce/{preset}', int(result['seed']), 0, 0, 0,
                    Variant(structure=tuple(result['structure'])), engine=engine)
    return task, genome_spec(task).encode(design)


def main():
    """Measure the design of a result file in one engine; write RUN-in-ENGINE.json."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('result', type=pathlib.Path)
    parser.add_argument('--preset', required=True, help='file name in config/reproduce/')
    parser.add_argument('--engine', required=True, choices=('pybullet', 'mujoco'))
    parser.add_argument('--out', required=True, type=pathlib.Path)
    parser.add_argument('--unseen', type=int, default=1000)
    parser.add_argument('--processes', type=int, default=1)
    arguments = parser.parse_args()
    result = json.loads(arguments.result.read_text())
    run = arguments.result.stem.removeprefix('result-')
    task, x = result_task_and_genome(result, arguments.preset, arguments.engine)
    lines, record = engine_report(str(arguments.result), task, x, tuple(result['structure']),
                                  arguments.unseen, arguments.processes, 'pybullet')
    arguments.out.mkdir(parents=True, exist_ok=True)
    target = arguments.out / f'{run}-in-{arguments.engine}.json'
    target.write_text(json.dumps(record, indent=1) + '\n')
    print('\n'.join(lines[:8]))
    print(f'wrote {target}')


if __name__ == '__main__':
    main()
