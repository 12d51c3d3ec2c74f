"""The robot component: the robot under test behind its watchdog, and its motors.

Every control tick (after the mission executor) it hands the controller an ``Observation``
of its view (``RobotView``: the sensors through the fault stage; the scan as a read-only
copy, one per scan), takes its velocity command, passes it through the fault stage and
clips it to the drive limits, as a motor driver saturates. It publishes both: what the
controller asked for (the belief's ``cmd``) and what reaches the motors (the world applies
it). The mission executor reaches the robot through its goal interface (``send_goal``,
``cancel_goal``, ``feedback``: the navigation action, a request/response pair rather than a
message). A controller that raises, hangs or breaks its contract raises ``ControllerFault``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rei.runtime.errors import RunError
from rei.runtime.messages import CommandIssued, LaserScan
from rei.runtime.robot.contract import (
    Controller,
    ControllerContext,
    GoalFeedback,
    NavGoal,
    Observation,
    read_only_scan,
)
from rei.runtime.robot.watchdog import GuardedController
from rei.runtime.simulation.faults.stage import FaultStage
from rei.runtime.simulation.loop.board import Board
from rei.runtime.simulation.loop.scheduler import Clock


@dataclass(frozen=True)
class Robot:
    controller: Controller
    context: ControllerContext
    watchdog: float | None
    """Wall-clock seconds a controller call may take; None runs it in the main thread."""
    max_linear: float
    """m/s: the drive's limit, lowered by the mission's max_speed."""
    max_angular: float
    faults: FaultStage

    def start(self, board: Board) -> RobotRun:
        return RobotRun(self, board)


class RobotRun:
    def __init__(self, spec: Robot, board: Board) -> None:
        self.spec, self.board = spec, board
        self.guard = GuardedController(spec.controller, spec.watchdog)
        self._source: LaserScan | None = None
        self._copy: LaserScan | None = None
        self._seq = 0

    def reset(self) -> None:
        """Hand the controller the run's context (before the first tick)."""
        self.guard.reset(self.spec.context)

    # the navigation action, for the mission executor
    def send_goal(self, goal: NavGoal) -> None:
        self.guard.send_goal(goal)

    def cancel_goal(self) -> None:
        self.guard.cancel_goal()

    def feedback(self) -> GoalFeedback:
        return self.guard.feedback()

    def step(self, clock: Clock) -> None:
        view = self.board.view
        assert view is not None
        if view.scan is not self._source:  # one read-only copy per scan
            self._source, self._copy = view.scan, read_only_scan(view.scan)
        raw = self.guard.step(Observation(clock.now, view.odom, view.odom_twist, self._copy,
                                          view.scan_time))
        linear, angular = self.spec.faults.command(clock.now, (raw.linear, raw.angular))
        if not (math.isfinite(linear) and math.isfinite(angular)):
            raise RunError(f"the fault stage sent a non-finite motor command "
                           f"({linear!r}, {angular!r}) at t={clock.now:g} s")
        vmax, wmax = self.spec.max_linear, self.spec.max_angular
        self.board.command = CommandIssued(
            self._seq, clock.now, (raw.linear, raw.angular),
            (min(max(linear, -vmax), vmax), min(max(angular, -wmax), wmax)))
        self._seq += 1

    def close(self) -> None:
        self.guard.close()
