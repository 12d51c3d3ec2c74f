"""The mission component: the mission executor (thesis 6.1.4) on the control clock.

Every control tick (after the faults component, before the robot) it tells the supervising
probe how far the run got, ticks the executor against the robot's goal interface and the
robot's true pose, and publishes the events and the navigation state; when the mission has
finished it ends the run. In the last tick the run may reach (its time limit, or the user's
duration limit) its deadline stage abandons the running task, after the robot's step. It
also measures the path the robot travelled (from the true pose, every control tick).

It asks for the robot's feedback twice a tick (the executor, to judge the running task; then
the state it publishes), after the robot's last step and before its next: between them only
the executor's own ``cancel_goal`` / ``send_goal`` can change the controller, so the robot
answers both from one computation made after its step or goal (``rei.runtime.robot.host``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

from rei.generators.concrete import ConcreteMission
from rei.runtime.messages import MissionEvent, MissionStatus, NavState, Pose
from rei.runtime.robot.behaviours import SPEED_LIMIT_SHARE, EpisodeLog, observed, reported
from rei.runtime.simulation.loop.board import Board
from rei.runtime.simulation.loop.scheduler import Clock
from rei.runtime.simulation.mission import MissionExecutor
from rei.runtime.simulation.mission.executor import GoalClient


class Probe(Protocol):
    def tick(self, time: float) -> None: ...


@dataclass(frozen=True)
class Mission:
    mission: ConcreteMission
    start_pose: Pose
    end_reason: str
    """Why the last tick ends the run: the time limit or the user's duration limit."""
    end_cause: str
    """The running task's failure cause then: 'abandoned', or 'cut' by a duration limit."""

    def start(self, board: Board, robot: GoalClient, probe: Probe | None,
              say: Callable[[str], None]) -> MissionRun:
        return MissionRun(self, board, robot, probe, say)


class MissionRun:
    def __init__(self, spec: Mission, board: Board, robot: GoalClient, probe: Probe | None,
                 say: Callable[[str], None]) -> None:
        self.spec, self.board, self.robot, self.probe, self.say = spec, board, robot, probe, say
        self.executor = MissionExecutor(spec.mission.tasks(), spec.mission.settle)
        self.path_length = 0.0
        self.timed_out = False
        self.behaviours = EpisodeLog()
        """The behaviours the run exercised (summary.json's ``behaviours``)."""
        self._last = spec.start_pose
        self._seq = 0

    def step(self, clock: Clock) -> None:
        truth = self.board.truth
        assert truth is not None
        pose = truth.pose
        self.path_length += math.hypot(pose[0] - self._last[0], pose[1] - self._last[1])
        self._last = pose
        if self.probe is not None:
            self.probe.tick(clock.now)
        events = self.executor.tick(clock.now, self.robot, pose)
        try:
            feedback = self.robot.feedback()
        except BaseException:  # the events happened: they reach the collector all the same
            self._publish(clock.now, events, *self._nav())
            raise
        self._publish(clock.now, events, feedback.state, self.executor.current_task)
        self._log_behaviours(clock.now, feedback.message if feedback.state is NavState.ACTIVE
                             else "")
        if self.executor.finished:
            clock.stop("mission finished")

    def _log_behaviours(self, now: float, message: str) -> None:
        """What the robot's last step did: what it reports and what its command shows (the
        command of the step the feedback answers for: this component runs before the robot)."""
        names = list(reported(message))
        command = self.board.command
        if command is not None:
            linear, angular = command.raw
            names += observed(linear, angular)
            limit = self.spec.mission.max_speed
            if limit is not None and abs(linear) >= SPEED_LIMIT_SHARE * limit:
                names.append("speed_limit")
        self.behaviours.tick(now, names)

    def deadline(self, clock: Clock) -> None:
        """The last tick: the time (or duration) limit ends the mission."""
        if clock.stopped:
            return
        if self.executor.settling and self.spec.end_cause == "abandoned":
            # The tasks are done; the time limit only cuts the settle period short.
            self._publish(clock.now, self.executor.end_settled(clock.now), *self._nav())
            clock.stop("mission finished")
            return
        self.abandon(clock.now, self.spec.end_reason, self.spec.end_cause)
        self.timed_out = True
        clock.stop(self.spec.end_reason)

    def abandon(self, now: float, reason: str, cause: str = "abandoned") -> None:
        """End the mission early, failing the running task."""
        truth = self.board.truth
        assert truth is not None
        self._publish(now, self.executor.abandon(now, reason, truth.pose, cause), *self._nav())

    def _nav(self) -> tuple[NavState, str | None]:
        """The navigation state as of the last completed tick."""
        status = self.board.status
        return (NavState.IDLE, None) if status is None else (status.nav_state, status.task)

    def _publish(self, now: float, events: list[MissionEvent], state: NavState,
                 task: str | None) -> None:
        for e in events:
            which = f" {e.task} (#{e.index})" if e.task is not None else ""
            why = f": {e.reason}" if e.reason else ""
            self.say(f"t={e.time:9.3f}  {e.kind}{which}{why}")
        status = MissionStatus(self._seq, now, tuple(events), state, task)
        self._seq += 1
        self.board.status = status
        if events:
            self.board.events.append(status)
