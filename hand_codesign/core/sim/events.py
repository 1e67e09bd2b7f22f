"""
The rollout loop both engines step through: when to look at the world, and what to do then.

An EventPlan merges the steps at which a rollout looks at its world: the goal schedule's
checks (object pose recorded; early termination, eq. 6; every check also watches the
object's stability), a stability watch twice per simulated second (the object; the joints
once a second and at the end: each watch costs about 0.1 % of the rollout), and frames for
replay when a callback is given. The rollout ends at the last goal: nothing after it is
scored.

`play` runs those events; between two of them the engine steps its physics its own way
(PyBullet one step at a time with the policy's torques, MuJoCo in runs of steps whose
torques stay the same), so the engines share every decision the loop makes and differ only
in how they step.
"""

from dataclasses import dataclass
import math

from hand_codesign.core.sim.scene import EXPLOSION_DISTANCE, EXPLOSION_JOINT_SPEED

WATCHES_PER_SECOND = 2.0  # object stability watches per simulated second, besides the checks
JOINT_WATCH_EVERY = 2  # joints are checked at every 2nd watch (once a second) and at the end

_RECORD, _WATCH, _JOINT_WATCH, _FRAME = 1, 2, 4, 8
_CACHED_PLANS = 16


@dataclass
class Rollout:
    """What one world's rollout produced."""

    trace: object  # objectives.Trace: object poses at the goal checks
    steps: int  # physics steps simulated
    unstable: bool
    final_position: tuple  # object pose at the end (last finite pose if unstable)
    final_orientation: tuple


class EventPlan:
    """The steps at which the rollout loop looks at the world, merged and flagged."""

    def __init__(self, schedule, time_step, frame_every=0):
        # Nothing after the last goal is scored: the rollout ends there.
        self.num_steps = (schedule.check_step_list[-1] if schedule.num_checks
                          else schedule.num_steps)
        events = {}
        for step in schedule.check_step_list:
            events[step] = events.get(step, 0) | _RECORD
        watch = max(1, int(round(1.0 / (WATCHES_PER_SECOND * time_step))))
        for step in range(watch, self.num_steps + 1, watch):
            events[step] = events.get(step, 0) | _WATCH
        for step in range(watch * JOINT_WATCH_EVERY, self.num_steps + 1,
                          watch * JOINT_WATCH_EVERY):
            events[step] |= _JOINT_WATCH
        if frame_every:
            for step in range(frame_every, self.num_steps + 1, frame_every):
                events[step] = events.get(step, 0) | _FRAME
        ordered = sorted(step for step in events if step <= self.num_steps)
        self.steps = tuple(ordered) + (-1,)  # -1: no further event
        self.kinds = tuple(events[step] for step in ordered) + (0,)


class EventPlans:
    """A simulator's cache of EventPlans, one per goal schedule and frame interval."""

    def __init__(self):
        self._plans = {}

    def plan(self, schedule, frame_every=0):
        """Return the EventPlan of a goal schedule (cached)."""
        key = (schedule, frame_every)  # schedules compare by identity
        plan = self._plans.get(key)
        if plan is None:
            plan = EventPlan(schedule, schedule.time_step, frame_every)
            if len(self._plans) > _CACHED_PLANS:
                self._plans.clear()
            self._plans[key] = plan
        return plan


def play(plan, trace, state, advance, object_pose, stable, on_frame=None, simulator=None):
    """
    Step one world's rollout through `plan`'s events; return its Rollout.

    `advance(done, stop)` steps the physics from step `done` to step `stop` (stop > done);
    `object_pose()` returns the object's (position, orientation x, y, z, w);
    `stable(position, orientation, start, check_joints)` is False once the world has blown
    up. `trace` (objectives.Trace) records the pose at every goal check and says when eq. 6
    ends the rollout early; `state` is the world's ObjectState. `on_frame(step, simulator)`
    is called at step 0 and at every frame event of the plan.
    """
    num_steps = plan.num_steps
    event_steps, event_kinds = plan.steps, plan.kinds
    start = state.position
    last_pose = (tuple(state.position), tuple(state.orientation))
    if on_frame is not None:
        on_frame(0, simulator)
    done = event = 0
    # An event at step 0 or below ends the events (the plan's last is -1): run to the end.
    while (next_event := event_steps[event]) > 0:
        if next_event > done:
            advance(done, next_event)
        done = next_event
        kind = event_kinds[event]
        position, orientation = object_pose()
        if not stable(position, orientation, start, kind & _JOINT_WATCH):
            return _ended(trace, done, True, last_pose)
        last_pose = (position, orientation)
        if kind & _FRAME:
            on_frame(done, simulator)
        if kind & _RECORD and trace.record(position, orientation):
            return _ended(trace, done, False, last_pose)
        event += 1
    if num_steps > done:
        advance(done, num_steps)
    position, orientation = object_pose()
    if stable(position, orientation, start, True):
        return _ended(trace, num_steps, False, (position, orientation))
    return _ended(trace, num_steps, True, last_pose)


def object_intact(position, orientation, start):
    """Return whether the object's pose is finite and within EXPLOSION_DISTANCE of `start`."""
    x, y, z = position
    return (math.isfinite(x + y + z + sum(orientation))
            and (x - start[0]) ** 2 + (y - start[1]) ** 2 + (z - start[2]) ** 2
            < EXPLOSION_DISTANCE ** 2)


def _ended(trace, steps, unstable, pose):
    return Rollout(trace=trace, steps=steps, unstable=unstable,
                   final_position=tuple(pose[0]), final_orientation=tuple(pose[1]))


def joints_intact(angles, speeds):
    """Return whether every joint angle (rad) is finite and every speed (rad/s) is sane."""
    # in Python: numpy's calls cost more than a hand's few joints
    return (all(map(math.isfinite, angles))
            and all(abs(speed) < EXPLOSION_JOINT_SPEED for speed in speeds))
