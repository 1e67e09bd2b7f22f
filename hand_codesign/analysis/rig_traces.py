"""
The measured trials a bag holds: each TrialRequest with the rig's events and its pose trace.

A rig evaluator's trials are recorded on the rig topics (core.contract.RIG_TOPIC_TYPES). A
pose carries no trial id: a rig runs one trial at a time, so a trial's trace is the poses
stamped from its start to its end (TrialStatus stamps, the poses' clock), as the rig
evaluator itself scored it.
"""

from dataclasses import dataclass

from hand_codesign.bag.reader import read_topics
from hand_codesign.core.contract import (OBJECT_POSE, RIG_TOPIC_TYPES, TRIAL_ENDED,
                                         TRIAL_FAILED, TRIAL_REQUESTS, TRIAL_START_COLLISION,
                                         TRIAL_STARTED, TRIAL_STATUS)
import numpy as np

OUTCOMES = {TRIAL_ENDED: 'ended', TRIAL_START_COLLISION: 'start collision',
            TRIAL_FAILED: 'failed'}


@dataclass
class TrialTrace:
    """One recorded trial and the object poses measured during it."""

    run_id: str
    candidate_id: int
    attempt: int
    evaluator_id: str
    trial_id: int
    world: int
    duration: float
    outcome: str             # 'ended', 'start collision', 'failed' or 'no answer'
    times: np.ndarray        # s from the trial's start
    positions: np.ndarray    # (samples, 3), m, world frame
    orientations: np.ndarray  # (samples, 4), x y z w


def trial_traces(path, run_id=None):
    """Return the TrialTraces of a bag (of one run if run_id is given), in request order."""
    tables, _ = read_topics(path, list(RIG_TOPIC_TYPES.values()))
    requests = tables[RIG_TOPIC_TYPES[TRIAL_REQUESTS]]
    status = tables[RIG_TOPIC_TYPES[TRIAL_STATUS]]
    poses = tables[RIG_TOPIC_TYPES[OBJECT_POSE]]
    events = {}
    for index in range(len(status)):
        row = status.row(index)
        key = (row['evaluator_id'], int(row['trial_id']))
        events.setdefault(key, {})[int(row['event'])] = int(row['stamp'])
    stamps = np.array([row[0] for row in poses['header']], dtype=np.int64) if len(poses) \
        else np.zeros(0, dtype=np.int64)
    pose_values = poses['pose'] if len(poses) else []
    traces = []
    for index in range(len(requests)):
        row = requests.row(index)
        if run_id is not None and row['run_id'] != run_id:
            continue
        heard = events.get((row['evaluator_id'], int(row['trial_id'])), {})
        outcome = next((name for event, name in OUTCOMES.items() if event in heard),
                       'no answer')
        start, end = heard.get(TRIAL_STARTED), heard.get(TRIAL_ENDED)
        chosen = (np.flatnonzero((stamps >= start) & (stamps <= end))
                  if start is not None and end is not None else np.zeros(0, dtype=int))
        chosen = chosen[np.argsort(stamps[chosen], kind='stable')]
        traces.append(TrialTrace(
            run_id=row['run_id'], candidate_id=int(row['candidate_id']),
            attempt=int(row['attempt']), evaluator_id=row['evaluator_id'],
            trial_id=int(row['trial_id']), world=int(row['world']),
            duration=float(row['duration']), outcome=outcome,
            times=(stamps[chosen] - (start or 0)) * 1e-9,
            positions=np.array([pose_values[i][0] for i in chosen], dtype=float).reshape(-1, 3),
            orientations=np.array([pose_values[i][1] for i in chosen],
                                  dtype=float).reshape(-1, 4)))
    return traces
