"""The mission executor: feeds the tasks to the robot one by one (thesis 4.3.2, 6.1.4, 6.2.3).

It sends each task's goal, waits for its result and emits the mission events the SIG_MISSION_*
signals come from. A task fails when the controller aborts or preempts it, when it outlives its
timeout (the goal is then cancelled), and when the controller claims success but the ground
truth puts the robot outside the goal's position tolerance or, for a goal with a heading,
turned farther from it than the heading tolerance. Every failure carries a human-readable
reason and a machine-readable cause (messages.FAILURE_CAUSES). Cycles repeat the goal
sequence. After the last task the mission goes on for its settle period (``settle`` seconds,
the .mission's ``settle``) before it ends: the robot is watched standing where it ended its
last task, so a navigator that never stops or drifts off after success is seen doing it. This
module must never import pybullet or judge anything but task outcomes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

from rei.generators.concrete import ConcreteGoal
from rei.runtime.messages import MissionEvent, NavState
from rei.runtime.robot.contract import GoalFeedback, NavGoal


class GoalClient(Protocol):
    def send_goal(self, goal: NavGoal) -> None: ...

    def cancel_goal(self) -> None: ...

    def feedback(self) -> GoalFeedback: ...


@dataclass(frozen=True)
class TaskResult:
    index: int
    task: str
    succeeded: bool
    reason: str
    start: float
    end: float
    final_distance: float
    cause: str = ""
    """One of messages.FAILURE_CAUSES when the task failed, else ''."""


class MissionExecutor:
    def __init__(self, tasks: tuple[ConcreteGoal, ...], settle: float = 0.0) -> None:
        self.tasks = tasks
        self.settle = settle
        self.results: list[TaskResult] = []
        self.begun = False
        self.finished = False
        self._current: int | None = None
        self._start = 0.0
        self._settle_from: float | None = None

    @property
    def settling(self) -> bool:
        """Every task has ended and the settle period runs."""
        return self._settle_from is not None and not self.finished

    def end_settled(self, time: float) -> list[MissionEvent]:
        """End the mission in its settle period (the time limit came first): the tasks are
        done, so this is an ordinary end, not an abandonment."""
        if not self.settling:
            return []
        self.finished = True
        return [MissionEvent("end", time)]

    @property
    def current_task(self) -> str | None:
        return self.tasks[self._current].name if self._current is not None else None

    def tick(self, time: float, client: GoalClient,
             truth: tuple[float, float, float]) -> list[MissionEvent]:
        """Advance the mission at simulation time ``time``; the events it emitted."""
        if self.finished:
            return []
        events = self._begin(time)
        if self._current is not None:
            goal = self.tasks[self._current]
            fb = client.feedback()
            distance = self._distance(truth)
            reason: str | None = None
            cause = ""
            ok = False
            if fb.state == NavState.SUCCEEDED:
                reason, cause = self._judge_arrival(goal, truth, distance)
                ok = not cause
            elif fb.state == NavState.ABORTED:
                reason = f"aborted: {fb.message}" if fb.message else "aborted"
                cause = "aborted"
            elif fb.state == NavState.PREEMPTED:
                reason, cause = "preempted", "preempted"
            elif time - self._start >= goal.timeout:
                client.cancel_goal()
                reason, cause = f"timeout after {goal.timeout:g} s", "timeout"
            if reason is not None:
                events.append(self._end_task(time, ok, reason, cause, distance))
        if self._current is None:
            next_index = len(self.results)
            if next_index < len(self.tasks):
                goal = self.tasks[next_index]
                self._current, self._start = next_index, time
                client.send_goal(NavGoal(goal.name, goal.x, goal.y, goal.yaw, goal.tolerance,
                                         goal.timeout))
                events.append(MissionEvent("task_start", time, goal.name, next_index))
            else:
                if self._settle_from is None:
                    self._settle_from = time
                if time - self._settle_from >= self.settle - 1e-9:
                    self.finished = True
                    events.append(MissionEvent("end", time))
        return events

    def _begin(self, time: float) -> list[MissionEvent]:
        """The 'begin' event the first time the mission is advanced or abandoned."""
        if self.begun:
            return []
        self.begun = True
        return [MissionEvent("begin", time)]

    @staticmethod
    def _judge_arrival(goal: ConcreteGoal, truth: tuple[float, float, float],
                       distance: float) -> tuple[str, str]:
        """(reason, cause) of a claimed success by the ground truth; ('', '') if it holds.

        The position is judged first: a robot in the wrong place has no heading worth naming.
        """
        if distance > goal.tolerance:
            return (f"outside tolerance: the robot is {distance:.3f} m from the goal, "
                    f"tolerance {goal.tolerance:g} m", "position")
        if goal.yaw is not None:
            off = abs(math.remainder(truth[2] - goal.yaw, math.tau))
            if off > goal.heading_tolerance:
                return (f"heading off by {math.degrees(off):.1f}° (tolerance "
                        f"{math.degrees(goal.heading_tolerance):g}°)", "heading")
        return "", ""

    def _distance(self, truth: tuple[float, float, float]) -> float:
        """Ground-truth distance from the robot to the running task's goal."""
        assert self._current is not None
        goal = self.tasks[self._current]
        return math.hypot(truth[0] - goal.x, truth[1] - goal.y)

    def _end_task(self, time: float, ok: bool, reason: str, cause: str,
                  distance: float) -> MissionEvent:
        assert self._current is not None
        index, goal = self._current, self.tasks[self._current]
        self.results.append(TaskResult(index, goal.name, ok, reason, self._start, time, distance,
                                       cause))
        self._current = None
        return MissionEvent("task_success" if ok else "task_fail", time, goal.name, index, reason,
                            cause)

    def abandon(self, time: float, reason: str, truth: tuple[float, float, float],
                cause: str = "abandoned") -> list[MissionEvent]:
        """End the mission early (time limit, error, interruption; ``cause`` 'cut' when the
        user's duration limit stopped the run): fail the running task."""
        if self.finished:
            return []
        events = self._begin(time)
        if self._current is not None:
            events.append(self._end_task(time, False, reason, cause,
                                         self._distance(truth)))
        self.finished = True
        events.append(MissionEvent("end", time, reason=reason))
        return events
