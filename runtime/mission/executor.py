"""The mission executor: feeds the tasks to the robot one by one (thesis 4.3.2, 6.1.4, 6.2.3).

It sends each task's goal, waits for its result and emits the mission events the SIG_MISSION_*
signals come from. A task fails when the controller aborts or preempts it, when it outlives its
timeout (the goal is then cancelled), and when the controller claims success but the ground
truth puts the robot outside the goal's tolerance. Cycles repeat the goal sequence. This module
must never import pybullet or judge anything but task outcomes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

from rei.generators.concrete import ConcreteGoal
from rei.runtime.messages import MissionEvent, NavState
from rei.runtime.robot.protocol import GoalFeedback, NavGoal


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


class MissionExecutor:
    def __init__(self, tasks: tuple[ConcreteGoal, ...]) -> None:
        self.tasks = tasks
        self.results: list[TaskResult] = []
        self.begun = False
        self.finished = False
        self._current: int | None = None
        self._start = 0.0

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
            ok = False
            if fb.state == NavState.SUCCEEDED:
                ok = distance <= goal.tolerance
                reason = "" if ok else (f"outside tolerance: the robot is {distance:.3f} m from "
                                        f"the goal, tolerance {goal.tolerance:g} m")
            elif fb.state == NavState.ABORTED:
                reason = f"aborted: {fb.message}" if fb.message else "aborted"
            elif fb.state == NavState.PREEMPTED:
                reason = "preempted"
            elif time - self._start >= goal.timeout:
                client.cancel_goal()
                reason = f"timeout after {goal.timeout:g} s"
            if reason is not None:
                events.append(self._end_task(time, ok, reason, distance))
        if self._current is None:
            next_index = len(self.results)
            if next_index < len(self.tasks):
                goal = self.tasks[next_index]
                self._current, self._start = next_index, time
                client.send_goal(NavGoal(goal.name, goal.x, goal.y, goal.yaw, goal.tolerance,
                                         goal.timeout))
                events.append(MissionEvent("task_start", time, goal.name, next_index))
            else:
                self.finished = True
                events.append(MissionEvent("end", time))
        return events

    def _begin(self, time: float) -> list[MissionEvent]:
        """The 'begin' event the first time the mission is advanced or abandoned."""
        if self.begun:
            return []
        self.begun = True
        return [MissionEvent("begin", time)]

    def _distance(self, truth: tuple[float, float, float]) -> float:
        """Ground-truth distance from the robot to the running task's goal."""
        assert self._current is not None
        goal = self.tasks[self._current]
        return math.hypot(truth[0] - goal.x, truth[1] - goal.y)

    def _end_task(self, time: float, ok: bool, reason: str, distance: float) -> MissionEvent:
        assert self._current is not None
        index, goal = self._current, self.tasks[self._current]
        self.results.append(TaskResult(index, goal.name, ok, reason, self._start, time, distance))
        self._current = None
        return MissionEvent("task_success" if ok else "task_fail", time, goal.name, index, reason)

    def abandon(self, time: float, reason: str,
                truth: tuple[float, float, float]) -> list[MissionEvent]:
        """End the mission early (time limit, error, interruption): fail the running task."""
        if self.finished:
            return []
        events = self._begin(time)
        if self._current is not None:
            events.append(self._end_task(time, False, reason, self._distance(truth)))
        self.finished = True
        events.append(MissionEvent("end", time, reason=reason))
        return events
