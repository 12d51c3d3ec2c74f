"""Controllers that drive a fixed way, for contact tests: into a body, or touch it and back.

Importable as `tests.robot.scripted:NAME`, like a user's controller. They accept every goal
and never end one (tasks time out or are abandoned): only the motion matters to the tests.
"""

from __future__ import annotations

from rei.runtime.robot import ControllerContext, Observation, VelocityCommand
from tests.robot.faulty import Idle


class Ram(Idle):
    """Drives straight ahead at ``speed`` (m/s); with ``bounce_at``, backs off at the same speed
    from the first step its odometry passes that x (a touch of a few physics steps when the
    control rate equals the physics rate and the odometry is exact)."""

    name = "ram"

    def __init__(self, speed: float = 0.2, bounce_at: float | None = None) -> None:
        super().__init__()
        self.speed = speed
        self.bounce_at = bounce_at
        self.backing = False

    def reset(self, context: ControllerContext) -> None:
        super().reset(context)
        self.backing = False

    def step(self, observation: Observation) -> VelocityCommand:
        if self.tracker.state.value == "pending":
            self.tracker.accept()
        if self.bounce_at is not None and observation.odom_pose[0] >= self.bounce_at:
            self.backing = True
        return VelocityCommand(-self.speed if self.backing else self.speed, 0.0)
