"""
An evaluator that holds its key and lies: the real evaluator node, with wrong objectives.

Started by test_system.py with its key (a key_file, as an evaluator on another host reads
it); every evaluation it signs and publishes has each objective 0.001 lower than the truth,
a "better" design that was never simulated as such.
"""

import dataclasses
import sys

from hand_codesign.core.evaluate import evaluate
from hand_codesign.ros import evaluator_node


def lying_evaluate(genome, task, worlds=None, on_world=None, share=None):
    truth = evaluate(genome, task, worlds, on_world, share)
    return dataclasses.replace(truth, objectives=truth.objectives - 1e-3,
                               fitness=truth.fitness - 1e-3)


if __name__ == '__main__':
    evaluator_node.evaluate = lying_evaluate
    sys.exit(evaluator_node.main())
