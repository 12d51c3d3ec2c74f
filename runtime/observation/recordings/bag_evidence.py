"""The evidence a ROS 2 recording gives of its mission: ``NavEvidence``, the goal client the
mission executor drives while a bag is read (Nav2's status when the bag has it, else the
ground truth), and ``TopicRate``, a topic's message times (gaps, stamps going backwards).
Read by rei.runtime.observation.recordings.foreign; this module must never import pybullet.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from rei.runtime.messages import NavState
from rei.runtime.robot.contract import GoalFeedback, NavGoal

GAP = 2.5
"""A stream whose messages are this many of its usual intervals apart has a gap (a rate
drop): what happened in between was not observed."""
class NavEvidence:
    """The mission executor's goal client for a recording: the navigation state the
    recording shows (Nav2's status, when the bag has it), else the state the ground truth
    gives (SUCCEEDED within the goal's tolerances); the executor then judges it as live."""

    def __init__(self, with_status: bool) -> None:
        self.with_status = with_status
        self.goal: NavGoal | None = None
        self.heading_tolerance = 0.0
        self.statuses: dict[bytes, tuple[float, int, NavState]] = {}
        """Nav2's goals: id -> (accepted at, first heard, state); the k-th goal accepted is
        the mission's k-th task (a mission runner sends them one by one)."""
        self.sent = -1
        self.truth = (0.0, 0.0, 0.0)

    def send_goal(self, goal: NavGoal) -> None:
        self.goal = goal
        self.sent += 1

    def status(self, key: bytes, accepted: float, state: NavState) -> None:
        first = self.statuses.get(key, (accepted, len(self.statuses), state))[1]
        self.statuses[key] = (accepted, first, state)

    def cancel_goal(self) -> None:
        self.goal = None

    def feedback(self) -> GoalFeedback:
        goal = self.goal
        if goal is None:
            return GoalFeedback(NavState.IDLE, None)
        if self.with_status:
            goals = sorted(self.statuses.values())
            state = goals[self.sent][2] if self.sent < len(goals) else NavState.PENDING
            return GoalFeedback(state, goal.name, message="Nav2's navigate_to_pose status")
        x, y, yaw = self.truth
        near = math.hypot(x - goal.x, y - goal.y) <= goal.tolerance
        turned = goal.yaw is None or \
            abs(math.remainder(yaw - goal.yaw, math.tau)) <= self.heading_tolerance
        return GoalFeedback(NavState.SUCCEEDED if near and turned else NavState.ACTIVE,
                            goal.name)


@dataclass
class TopicRate:
    """A topic's message times: its usual interval, and gaps and stamps going backwards."""

    last: float | None = None
    intervals: list[float] = field(default_factory=list)

    def see(self, time: float) -> str:
        last, self.last = self.last, time
        if last is None or not math.isfinite(time) or not math.isfinite(last):
            return ""
        dt = time - last
        if dt < 0:
            return f"its stamps go backwards ({last:.3f} s, then {time:.3f} s)"
        usual = float(np.median(self.intervals)) if len(self.intervals) >= 5 else None
        if len(self.intervals) < 50:
            self.intervals.append(dt)
        if usual is not None and usual > 0 and dt > GAP * usual:
            return (f"a gap of {dt:.3f} s (its messages are usually {usual:.3f} s apart): "
                    f"nothing was observed in between")
        return ""
