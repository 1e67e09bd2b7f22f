"""
Sub-problems of growing horizon: what the search follows on a task with early termination.

The paper "divides the optimization into ten sub-problems per second", conducted in order,
each evaluated at its end. Here sub-problem H (a horizon, s) evaluates every candidate as if
early termination had stopped its rollout at H: eq. (6) with t_stop = H, the goal samples up to
H scored and the rest charged a_o s_o. The horizon starts at `early_termination.horizon.start`
and grows by `step` once `share` of a generation tracks the goals up to H within the margins
on average, i.e. scores at most `GoalSchedule.margin_values()` (every sample missed by exactly
s_o) in every objective. It ends at the last goal, where the rollout is whole and scored by
eq. (5).

Why (measured with `python bench/bench_horizon.py`, seed 2, 12 candidates on 4 worlds): on
Task 3 the capsule does not fall freely (4.9 cm in 0.1 s) but drops 1.3 cm onto the palm
within 0.1 s and lies still; the orientation goal turns away from it and misses
theta_s = 0.3 rad at t = 0.4 s (18 degrees), where nearly every rollout stops. The fingers
(joint limits near their zero centre at the start) rarely touch it before then, so most
candidates read the same poses: in 30 generations the generation's best is the untouched
capsule, 0.04633, every time, and a generation has 2 to 9 distinct objective vectors among
7 to 12 collision-free candidates. Task 2's sphere misses its turning goal the same way at
0.3 to 0.5 s, so its goals after 1 s are only charged. A growing horizon alone does not change
that when termination still acts at every check inside it (`horizon-stops` in the bench):
every rollout still stops at 0.4 s and, on Task 2, the horizon stalls at 0.5 s. So inside the
horizon the rollout is not stopped; termination acts only at the horizon's end (the rollout
ends there). A design whose fingers slow, hold or turn the object scores better than one
whose object drifts, by how far it drifts, and the charges for the goals beyond H are the
same for every design. Measured: Task 3's generations at horizons 0.6 to 0.7 s have as many
distinct objective vectors as collision-free candidates (its best does not improve within 30
generations of 12); on Task 2 the best design after 6 generations scores 0.62 on the whole
rollout (eq. 5) against 0.80 for the best design of the plain search, at 0.76 times its
simulated seconds per candidate (seeds 3 and 4: 0.74 against 0.87, 0.65 against 0.90;
stopping inside the horizon: 0.74, 0.78, 0.66). On eq. (6) as the task states it, the plain
search's own target, the plain best stays ahead (1.64 against 1.70 for seed 2). The price:
rollouts no longer stop where a goal is first missed, so late horizons cost whole rollouts
(Task 3 after 30 generations at 0.7 s: 1.7 times the plain search's simulated seconds per
candidate).

Scores stay comparable across horizons: a design tracking within the margins from H1 to
H2 > H1 scores lower at H2 than at H1 (each charge s_o is replaced by an error below s_o), one
that does not scores higher. So pycma's best so far and MO-CMA-ES's (mu + lambda) parents, told
at an earlier horizon, remain valid yardsticks: a later design replaces them only by tracking
the new goals within the margins (or, with several objectives, by being better in one). So a
run's best design may have been told at an earlier horizon; result.json, analyze and replay
name its horizon.

The rule is a function of the objectives the optimizer was told, in order, so resume and
analysis re-derive every horizon by replaying the told objectives (core.search.optimizers.replay);
each candidate carries its horizon (Candidate.horizon, the Candidate message's `horizon`) and
is evaluated with `task.replace(horizon=...)`, so any evaluator computes the same numbers.
"""

import math

from hand_codesign.core.sim.objectives import goal_schedule
import numpy as np

TOLERANCE = 1e-12  # objectives at the margins' score within rounding count as tracking


class Horizon:
    """The horizon of the next generation of a task with early_termination.horizon."""

    def __init__(self, task):
        spec = task.early_termination.horizon
        self.task = task
        self.spec = spec
        self.end = float(goal_schedule(task).check_times[-1])  # the last goal
        self.current = min(spec.start, self.end)
        self.history = []  # the horizon of every generation told, in order
        self._tasks = {}

    def task_at(self, horizon, base=None):
        """Return the task (`base`'s, default the task's) of the sub-problem `horizon` (cached)."""
        base = self.task if base is None else base
        key = (horizon, base.stage)
        task = self._tasks.get(key)
        if task is None:
            task = self._tasks[key] = base.replace(horizon=horizon)
        return task

    @property
    def batch_task(self):
        """Return the task of the current sub-problem."""
        return self.task_at(self.current)

    def tracking(self, objectives):
        """Return per row of `objectives` whether it tracks the current horizon's goals."""
        yardstick = goal_schedule(self.batch_task).margin_values()
        objectives = np.asarray(objectives, dtype=float).reshape(-1, yardstick.size)
        return np.all(objectives <= yardstick + TOLERANCE, axis=1)

    def told(self, objectives):
        """Take the told objectives (rows) of a generation; grow the horizon if mastered."""
        tracking = self.tracking(objectives)
        self.history.append(self.current)
        needed = math.ceil(self.spec.share * len(tracking) - 1e-9)
        if self.current < self.end and int(tracking.sum()) >= needed:
            self.current = min(self.end, round(self.current + self.spec.step, 9))
