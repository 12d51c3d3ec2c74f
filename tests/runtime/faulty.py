"""Controllers that break the contract on purpose, for the watchdog and error tests.

They are importable as `tests.runtime.faulty:NAME`, the way a user names their own controller.
"""

from __future__ import annotations

import threading

from rei.runtime.robot import ControllerContext, GoalFeedback, NavGoal, Observation, VelocityCommand
from rei.runtime.robot.protocol import GoalTracker


class _Base:
    name = "faulty"

    def __init__(self) -> None:
        self.tracker = GoalTracker()
        self.calls = 0

    def reset(self, context: ControllerContext) -> None:
        self.tracker = GoalTracker()
        self.calls = 0

    def send_goal(self, goal: NavGoal) -> None:
        self.tracker.send(goal)

    def cancel_goal(self) -> None:
        self.tracker.cancel()

    def feedback(self) -> GoalFeedback:
        return self.tracker.feedback()

    def step(self, observation: Observation) -> VelocityCommand:
        self.calls += 1
        if self.tracker.state.value == "pending":
            self.tracker.accept()
        if self.calls >= 20:
            return self.fault()
        return VelocityCommand(0.1, 0.0)

    def fault(self) -> VelocityCommand:
        raise NotImplementedError


class Hanging(_Base):
    """Sleeps forever at its 20th step."""

    def fault(self) -> VelocityCommand:
        threading.Event().wait()
        return VelocityCommand(0.0, 0.0)


class Raising(_Base):
    def fault(self) -> VelocityCommand:
        raise ValueError("the planner lost its map")


class NonFinite(_Base):
    def fault(self) -> VelocityCommand:
        return VelocityCommand(float("nan"), 0.0)


class Interrupting(_Base):
    """Stands for the user pressing Ctrl-C during the run."""

    def fault(self) -> VelocityCommand:
        raise KeyboardInterrupt


class Slow(_Base):
    """Drives slowly in wall-clock time (10 ms per step), so a test can interrupt it."""

    def step(self, observation: Observation) -> VelocityCommand:
        if self.tracker.state.value == "pending":
            self.tracker.accept()
        threading.Event().wait(0.01)
        return VelocityCommand(0.05, 0.1)


class Idle(_Base):
    """Accepts goals and never moves: every task times out."""

    def step(self, observation: Observation) -> VelocityCommand:
        if self.tracker.state.value == "pending":
            self.tracker.accept()
        return VelocityCommand(0.0, 0.0)


class ClaimsSuccess(_Base):
    """Claims every goal at once without moving: the executor must check the ground truth."""

    def step(self, observation: Observation) -> VelocityCommand:
        if self.tracker.state.value == "pending":
            self.tracker.accept()
        if self.tracker.state.value == "active":
            self.tracker.succeed()
        return VelocityCommand(0.0, 0.0)


class AbortsAtOnce(_Base):
    """Accepts every goal and aborts it at once, standing still: it never touches anything,
    so only a requirement on the goals can tell that it did nothing."""

    def step(self, observation: Observation) -> VelocityCommand:
        if self.tracker.state.value == "pending":
            self.tracker.accept()
        if self.tracker.state.value == "active":
            self.tracker.abort("no path to the goal")
        return VelocityCommand(0.0, 0.0)
