"""
A reproduce campaign's committed design measured on its unseen worlds in one physics engine.

A campaign keeps each run's best design in `result-RUN.json` (key 'design': gene name -> value)
even when the run's bag is gone. This rebuilds the run's task from a pinned preset of
config/reproduce/ with the run's seed, encodes the design into its genome
(campaign.measures.result_design) and measures it on the same unseen worlds as `hand-codesign
analyze BAG --unseen N --engine ENGINE` (the same record, analysis.unseen.engine_report),
written as FOLDER/RUN-in-ENGINE.json for `hand-codesign transfer FOLDER`.

Usage: python tools/measure_result_design.py RESULT.json --preset task6_palm_beside.yaml
       --engine mujoco --out FOLDER [--unseen 1000] [--processes 1]   (from the repository's root)
"""

import argparse
import json
import pathlib

from hand_codesign.analysis.unseen import engine_report
from hand_codesign.campaign.measures import result_design


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
    task, x = result_design(result, arguments.preset, arguments.engine)
    lines, record = engine_report(str(arguments.result), task, x, tuple(result['structure']),
                                  arguments.unseen, arguments.processes, 'pybullet')
    arguments.out.mkdir(parents=True, exist_ok=True)
    target = arguments.out / f'{run}-in-{arguments.engine}.json'
    target.write_text(json.dumps(record, indent=1) + '\n')
    print('\n'.join(lines[:8]))
    print(f'wrote {target}')


if __name__ == '__main__':
    main()
