"""Planning defects: the navigator plans for a robot, or a world, other than the real one."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from rei.runtime.messages import NavState
from rei.runtime.robot.contract import ControllerContext, Observation, VelocityCommand
from rei.runtime.robot.navigator.gridplan import GridGraph
from rei.runtime.robot.navigator.reference import COMFORT, ReferenceNavigator

FOOTPRINT_SCALE = 0.5
"""FootprintTooSmall plans with the footprint scaled by this along both axes."""
REPLAN_PERIOD = 1.0
"""Seconds between NeverClearsObstacles' re-plans (Nav2's default tree re-plans at 1 Hz)."""
GHOST_CELL = 0.1
"""Metres: NeverClearsObstacles keeps one remembered point per cell of this size."""


class FootprintTooSmall(ReferenceNavigator):
    """Defect: plans and checks its motions with a footprint half the robot's size and no
    extra cost near obstacles (inflation radius no bigger than that footprint), so its
    shortest paths hug furniture and cut corners the real robot does not fit round.

    Imitates: a footprint / robot_radius and inflation radius copied from a smaller robot's
    configuration.

    Expected catcher: the collision requirements (MISSION_SIMPLE, MISSION_SEQUENCE_CYCLE,
    GEOM_COLLISION_LASER_CORRECT).
    """

    name = "footprint-too-small"

    def reset(self, context: ControllerContext) -> None:
        w, h = context.robot_size
        super().reset(replace(context, robot_size=(w * FOOTPRINT_SCALE, h * FOOTPRINT_SCALE)))

    def _grid_graph(self, inflate: float) -> GridGraph:
        # Every free cell costs as much as one far from obstacles: no inflation gradient.
        clear = self._clear
        self._clear = np.where(clear > inflate, COMFORT + 1.0, clear)
        try:
            return super()._grid_graph(inflate)
        finally:
            self._clear = clear


class NeverClearsObstacles(ReferenceNavigator):
    """Defect: marks every laser point the static map does not explain (a person, a moving
    object) as an obstacle for good, and re-plans around all of them once a second: the
    trail a person walked stays in its map as a wall of "ghost" obstacles, and its global
    path detours round places the person left long ago. When the ghosts shut every way it
    plans on the static map (as a costmap-clearing recovery would) and tries again a second
    later.

    Imitates: an obstacle layer that marks but never clears (``clearing: False``, or a
    raytrace range shorter than the marking range, so free space is never traced through),
    under a planner that re-plans periodically (Nav2's default behaviour tree, 1 Hz).

    Expected catcher: EFFICIENT_PATH (the detours round the ghosts), TIME_TO_GOAL; in rooms
    with people or moving objects only.
    """

    name = "never-clears-obstacles"

    def reset(self, context: ControllerContext) -> None:
        super().reset(context)
        self._ghosts: set[tuple[int, int]] = set()
        self._next_replan = 0.0

    def step(self, observation: Observation) -> VelocityCommand:
        tracker = self._tracker
        pose = observation.odom_pose
        points = self._laser_points(observation)
        if len(points):
            x, y, yaw = pose
            c, s = math.cos(yaw), math.sin(yaw)
            seen = points[self._unmapped(points, pose)]
            wx = x + c * seen[:, 0] - s * seen[:, 1]
            wy = y + s * seen[:, 0] + c * seen[:, 1]
            self._ghosts.update(zip(np.round(wx / GHOST_CELL).astype(int).tolist(),
                                    np.round(wy / GHOST_CELL).astype(int).tolist(),
                                    strict=True))
        if (tracker.state == NavState.ACTIVE and tracker.goal is not None and self._ghosts
                and observation.time >= self._next_replan):
            self._next_replan = observation.time + REPLAN_PERIOD
            self._pose = pose  # _replan_around reads the points from this pose
            x, y, yaw = pose
            ghosts = np.array(sorted(self._ghosts), dtype=float) * GHOST_CELL
            c, s = math.cos(yaw), math.sin(yaw)
            dx, dy = ghosts[:, 0] - x, ghosts[:, 1] - y
            # _replan_around takes points in the robot's frame, as the laser gives them.
            here = np.stack((c * dx + s * dy, -s * dx + c * dy), axis=1)
            self._replan_around(here, tracker.goal, (x, y))
        return super().step(observation)
