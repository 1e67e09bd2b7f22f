"""
Cost of signing: HMAC-SHA256 over the canonical bytes of a message against its CDR serialization.

Measures, in one run, per message of a Task 5 run (24 genes, one objective, 64 worlds):
- rclpy's CDR serialization of the Candidate and of the Evaluation (what DDS does anyway);
- the optimizer signing a Candidate and checking an Evaluation (core.run.signing);
- an evaluator checking a Candidate and signing its Evaluation.
Prints microseconds per message and the ratio of signing and checking to serializing.

Usage: python bench/bench_signing.py [--repeat 2000]
"""

import argparse
import time

from hand_codesign.core.run.signing import new_secret
from hand_codesign.core.run.signing import RunKeys
from hand_codesign.ros.keys import OptimizerSigner
from hand_codesign.ros.keys import sign_evaluation
from hand_codesign_msgs.msg import Candidate
from hand_codesign_msgs.msg import Evaluation
from hand_codesign_msgs.msg import RunInfo
import numpy as np
from rclpy.serialization import serialize_message


def per_call(function, repeat):
    """Return the seconds per call of function, best of three rounds."""
    best = float('inf')
    for _ in range(3):
        started = time.perf_counter()
        for _ in range(repeat):
            function()
        best = min(best, (time.perf_counter() - started) / repeat)
    return best


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--repeat', type=int, default=2000)
    repeat = parser.parse_args().repeat
    rng = np.random.default_rng(0)
    keys = RunKeys(new_secret())
    signer = OptimizerSigner(keys)
    signer.run_info(RunInfo(run_id='bench', task_yaml='x' * 4000, objective_names=['p']))
    credential = keys.credential('evaluator-0')
    candidate = signer.candidate(Candidate(
        run_id='bench', candidate_id=12345, evaluator_id='evaluator-0', structure=[2, 2],
        genome=rng.random(24).tolist(), genome_names=[f'gene.{i}' for i in range(24)]))
    evaluation = sign_evaluation(credential, Evaluation(
        run_id='bench', candidate_id=12345, evaluator_id='evaluator-0', objectives=[0.1],
        objective_names=['p'], world_objectives=rng.random(64).tolist()))
    serialize = per_call(lambda: (serialize_message(candidate), serialize_message(evaluation)),
                         repeat)
    optimizer = per_call(lambda: (signer.candidate(candidate), signer.valid(evaluation)), repeat)
    evaluator = per_call(lambda: (credential.candidate_valid(candidate, signer.digest),
                                  sign_evaluation(credential, evaluation)), repeat)
    assert signer.valid(evaluation) and credential.candidate_valid(candidate, signer.digest)
    print('per candidate (one Candidate and its Evaluation), microseconds')
    print(f'  CDR serialization of both (rclpy)      {serialize * 1e6:8.1f}')
    print(f'  optimizer: sign + check                {optimizer * 1e6:8.1f}   '
          f'ratio to serialization {optimizer / serialize:.2f}')
    print(f'  evaluator: check + sign                {evaluator * 1e6:8.1f}   '
          f'ratio to serialization {evaluator / serialize:.2f}')


if __name__ == '__main__':
    main()
