"""`teleop`: scripted velocity sequences, the dashboard drives of thesis 7.2.

``teleop`` / ``teleop:forward_backward`` drives straight ahead and back again (thesis 7.2.2:
towards a wall, into it, and away); ``teleop:circle`` drives circles (thesis 7.2.3). The
script starts at the first goal and runs once; every goal stays ACTIVE until the script has
ended and then SUCCEEDS, so the mission executor judges by ground truth whether the robot
is where the goal wanted it. This module must never import pybullet.
"""

from __future__ import annotations

from dataclasses import dataclass

from rei.runtime.robot.contract import (
    STOP,
    ControllerContext,
    GoalFeedback,
    GoalTracker,
    NavGoal,
    Observation,
    VelocityCommand,
)


@dataclass(frozen=True)
class Segment:
    duration: float
    linear: float
    angular: float


SCRIPTS: dict[str, tuple[Segment, ...]] = {
    # 0.2 m/s for 14 s: from the start tile of simple_wall into the east wall (it touches
    # after about 11.8 s and is held there), then 11.8 s back to where it started.
    "forward_backward": (Segment(14.0, 0.2, 0.0), Segment(1.0, 0.0, 0.0),
                         Segment(11.8, -0.2, 0.0)),
    # One and a half circles of radius 0.2/0.4 = 0.5 m, then the same the other way.
    "circle": (Segment(12.0, 0.2, 0.4), Segment(12.0, 0.2, -0.4)),
}


class TeleopController:
    def __init__(self, script: str = "forward_backward") -> None:
        if script not in SCRIPTS:
            raise KeyError(script)
        self.name = f"teleop:{script}"
        self.script = SCRIPTS[script]
        self._tracker = GoalTracker()
        self._start: float | None = None

    def reset(self, context: ControllerContext) -> None:
        self._tracker = GoalTracker()
        self._start = None
        self._ended = False

    def send_goal(self, goal: NavGoal) -> None:
        self._tracker.send(goal)

    def cancel_goal(self) -> None:
        self._tracker.cancel()

    def feedback(self) -> GoalFeedback:
        return self._tracker.feedback()

    def step(self, observation: Observation) -> VelocityCommand:
        tracker = self._tracker
        if tracker.state.value == "pending":
            tracker.accept()
        if self._start is None:
            if not tracker.running:
                return STOP
            self._start = observation.time
        elapsed = observation.time - self._start
        for seg in self.script:
            if elapsed < seg.duration:
                return VelocityCommand(seg.linear, seg.angular)
            elapsed -= seg.duration
        if tracker.state.value == "active":
            tracker.succeed("script finished")
        return STOP
