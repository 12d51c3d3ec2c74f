"""Localisation defects: the navigator believes it is somewhere it is not."""

from __future__ import annotations

from dataclasses import replace

from rei.runtime.robot.contract import Observation, VelocityCommand
from rei.runtime.robot.navigator.reference import ReferenceNavigator

ODOM_OFFSET = (0.35, 0.0)
"""Metres OdometryOffset adds to the odometry position (map frame)."""


class OdometryOffset(ReferenceNavigator):
    """Defect: uses its odometry position shifted by 0.35 m along the map's x axis for
    planning and control, so it stops beside its goals and plans too close to walls.

    Imitates: a wrong static transform between the map and odometry frames (a map origin
    entered off by a few cells, a transform applied twice).

    Expected catcher: MISSION_GOALS_REACHED / task failures ("outside tolerance"); the
    collision requirements where it plans too close to walls.
    """

    name = "odometry-offset"

    def step(self, observation: Observation) -> VelocityCommand:
        x, y, yaw = observation.odom_pose
        shifted = (x + ODOM_OFFSET[0], y + ODOM_OFFSET[1], yaw)
        return super().step(replace(observation, odom_pose=shifted))
