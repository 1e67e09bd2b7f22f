"""
Benchmark of the optimizer's cost of a Candidate's physical design against its evaluation.

Every Candidate carries its design in SI units, its standard URDF and its controller
(core.sim.physical.candidate_design, called once per candidate by core.run.controller). Measures
that per candidate, the Candidate message built and serialized with and without it, and as the
reference, measured in the same run, one evaluation of the same candidates with
core.evaluate on the task's world states. Prints the costs and their ratio to the evaluation.

    python bench/bench_physical.py [--task config/tasks/task1.yaml] [--candidates 200]
        [--world-states 16] [--evaluations 3]
"""

import argparse
import pathlib
import sys
import time

from hand_codesign.core import genome_spec, load_task, TaskError
from hand_codesign.core.evaluate import evaluate
from hand_codesign.core.search.optimizers import Candidate
from hand_codesign.core.sim.physical import candidate_design
from hand_codesign.core.task.variant import Variant
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]


def per_item(function, items):
    """Return the CPU seconds per item of function over items."""
    start = time.process_time()
    for item in items:
        function(item)
    return (time.process_time() - start) / len(items)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--task', default=str(ROOT / 'config' / 'tasks' / 'task1.yaml'))
    parser.add_argument('--candidates', type=int, default=200)
    parser.add_argument('--world-states', type=int, default=16)
    parser.add_argument('--evaluations', type=int, default=3)
    arguments = parser.parse_args(argv)
    try:
        task = load_task(arguments.task).replace(num_world_states=arguments.world_states)
    except TaskError as error:
        print(f'bench_physical: {error}', file=sys.stderr)
        return 2
    from hand_codesign.ros.conversions import candidate_message
    from rclpy.serialization import serialize_message
    spec = genome_spec(task)
    generator = np.random.default_rng(0)
    genomes = [spec.initial_mean() + 0.2 * generator.normal(size=spec.size)
               for _ in range(arguments.candidates)]
    candidates = [Candidate(candidate_id=index, generation=0, x=x,
                            variant=Variant(structure=task.structure))
                  for index, x in enumerate(genomes)]
    designs = [candidate_design(task, x) for x in genomes]   # warm up
    physical = per_item(lambda x: candidate_design(task, x), genomes)

    def message(candidate, design=None):
        return serialize_message(candidate_message('run', candidate, spec.names, '', 0, design))

    per_item(message, candidates)   # warm up the message classes and the serializer
    bare = per_item(message, candidates)
    full = per_item(lambda pair: message(*pair), list(zip(candidates, designs)))
    size = len(message(candidates[0], designs[0])) - len(message(candidates[0]))
    evaluation = per_item(lambda x: evaluate(x, task), genomes[:arguments.evaluations])
    print(f'task {task.name}, structure {list(task.structure)}, {arguments.candidates} '
          f'candidates; reference: evaluate on {task.num_world_states} worlds '
          f'{evaluation * 1e3:.1f} ms per candidate (CPU)')
    print(f'physical design (decode, URDF, controller): {physical * 1e3:.3f} ms per candidate '
          f'= {physical / evaluation:.2%} of an evaluation')
    print(f'Candidate message serialized: {bare * 1e3:.3f} ms without, {full * 1e3:.3f} ms '
          f'with the physical fields (+{size} bytes); the whole optimizer-side addition is '
          f'{(physical + full - bare) / evaluation:.2%} of an evaluation')
    return 0


if __name__ == '__main__':
    sys.exit(main())
