"""The range a laser beam would measure in the static map alone (ray casting against it).

A navigator tells what its laser sees that the map does not explain (a person, a moving
object) by comparing each beam with the map. A point near a map obstacle looks explained by
it, but a beam that ends well short of where the map says it should is stopped by something
the map does not have: a person standing against a wall or a pillar, on the robot's side of
it. ``MapCaster`` answers that comparison with the laser model's own ray casting
(``rei.runtime.sensors.laser``), over the boxes and cylinders of the map the robot was given.
This module must never import pybullet, and never read anything but that map.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from rei.runtime.robot.protocol import MapObstacle
from rei.runtime.sensors.laser import ray_boxes, ray_circles


class MapCaster:
    """Ray casting against the boxes and cylinders of a static map (immutable once built)."""

    def __init__(self, obstacles: Sequence[MapObstacle], grow: float = 0.0) -> None:
        """``grow``: metres every obstacle is cast as larger, so that a beam which grazes a
        corner exactly still hits it whatever the rounding of its direction."""
        self._boxes = np.array([(o.x, o.y, o.yaw, o.size_x / 2 + grow, o.size_y / 2 + grow)
                                for o in obstacles if o.shape != "cylinder"],
                               dtype=float).reshape(-1, 5)
        self._circles = np.array([(o.x, o.y, o.radius + grow) for o in obstacles
                                  if o.shape == "cylinder"], dtype=float).reshape(-1, 3)
        self._box_reach = np.hypot(self._boxes[:, 3], self._boxes[:, 4])

    def ranges(self, origin: tuple[float, float], directions: np.ndarray,
               max_range: float) -> np.ndarray:
        """Distance (N,) from ``origin`` along each unit direction (N, 2; world frame) to the
        first map obstacle, ``inf`` beyond ``max_range``; 0 from inside an obstacle."""
        if not len(directions):
            return np.zeros(0)
        o = np.array(origin, dtype=float)
        # Only the shapes a beam of max_range can reach (a room has hundreds of wall tiles).
        box_d = np.hypot(self._boxes[:, 0] - o[0], self._boxes[:, 1] - o[1])
        circle_d = np.hypot(self._circles[:, 0] - o[0], self._circles[:, 1] - o[1])
        boxes = self._boxes[box_d <= max_range + self._box_reach]
        circles = self._circles[circle_d <= max_range + self._circles[:, 2]]
        best = np.minimum(ray_boxes(o, directions, boxes), ray_circles(o, directions, circles))
        return np.where(best <= max_range, best, math.inf)
