"""A committed result's design rebuilt without its bag: the same task and gene values."""

import json
import pathlib

from hand_codesign.campaign.measures import result_design
from hand_codesign.core.task.genome import genome_spec
import numpy as np

RESULT = (pathlib.Path(__file__).resolve().parents[2] / 'docs' / 'results' / 'task6-rotation-paper'
          / 'seed104' / 'result-torque-cma-128w-seed104.json')


def test_a_committed_result_decodes_to_its_recorded_design_in_either_engine():
    result = json.loads(RESULT.read_text())
    recorded = result['design']
    for engine in ('pybullet', 'mujoco'):
        task, x = result_design(result, 'task6_palm_beside.yaml', engine)
        assert task.seed == 104 and task.physics.engine == engine
        values = genome_spec(task).design_values(x)
        assert values.keys() == recorded.keys()
        np.testing.assert_allclose([values[name] for name in recorded], list(recorded.values()),
                                   rtol=0, atol=1e-12)
