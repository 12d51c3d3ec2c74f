"""Perception defects: the navigator does not see what its laser sees."""

from __future__ import annotations

import math

import numpy as np

from rei.runtime.robot.contract import Observation
from rei.runtime.robot.navigator.reference import ReferenceNavigator

BLIND_FROM = math.radians(60.0)
BLIND_TO = math.radians(120.0)
"""The sector (bearing from the laser, counter-clockwise from ahead) whose beams are dropped."""


class IgnoresHumans(ReferenceNavigator):
    """Defect: drops every laser point the static map does not explain (farther than
    ``UNMAPPED_BEYOND`` from every map obstacle), so people and moving objects are invisible
    to the local planner, the recovery and the slow zone alike.

    Imitates: a costmap built from the static layer alone (obstacle layer disabled, or its
    laser topic remapped to nothing), a classic misconfiguration that goes unnoticed in empty
    test rooms.

    Expected catcher: the human collision requirements (MISSION_WITH_HUMAN_TRAJECTORY and the
    collision ones), HUMAN_SLOW_ZONE; only in missions with humans or dynamic objects.
    """

    name = "ignores-humans"

    def _laser_points(self, observation: Observation) -> np.ndarray:
        points = super()._laser_points(observation)
        kept: np.ndarray = points[~self._unmapped(points, self._scan_pose)]
        return kept


class BlindSector(ReferenceNavigator):
    """Defect: ignores the beams between 60 and 120 degrees to the left of the laser.

    Imitates: a laser angular-bounds filter configured for another mounting (meant to cut out
    a mast), or a scanner window blocked by a cable on one side.

    Expected catcher: REACTION_TIME when a person or a moving object shows up ahead on its
    left (60-90 degrees: ahead, and in the dropped sector); HUMAN_SLOW_ZONE when a person
    passes on its left; the collision requirements (MISSION_SIMPLE,
    GEOM_COLLISION_LASER_CORRECT, NO_ROBOT_COLLISION) when the robot turns left next to an
    obstacle.
    """

    name = "blind-sector"

    def _laser_points(self, observation: Observation) -> np.ndarray:
        points = super()._laser_points(observation)
        laser = self._ctx.laser  # type: ignore[union-attr]
        bearing = np.arctan2(points[:, 1] - laser.mount_y, points[:, 0] - laser.mount_x)
        kept: np.ndarray = points[(bearing < BLIND_FROM) | (bearing > BLIND_TO)]
        return kept
