"""Planning defects: the navigator plans for a robot that is not the one it drives."""

from __future__ import annotations

from dataclasses import replace

from rei.runtime.robot.protocol import ControllerContext
from rei.runtime.robot.reference import ReferenceNavigator

FOOTPRINT_SCALE = 0.5
"""FootprintTooSmall plans with the footprint scaled by this along both axes."""


class FootprintTooSmall(ReferenceNavigator):
    """Defect: plans and checks its motions with a footprint half the robot's size, so its
    inflation is too small: paths cut corners and graze walls and furniture.

    Imitates: a footprint / robot_radius copied from a smaller robot's configuration.

    Expected catcher: the collision requirements (MISSION_SIMPLE, MISSION_SEQUENCE_CYCLE,
    GEOM_COLLISION_LASER_CORRECT).
    """

    name = "footprint-too-small"

    def reset(self, context: ControllerContext) -> None:
        w, h = context.robot_size
        super().reset(replace(context, robot_size=(w * FOOTPRINT_SCALE, h * FOOTPRINT_SCALE)))
