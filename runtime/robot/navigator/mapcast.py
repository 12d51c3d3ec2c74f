"""The range a laser beam would measure in the static map alone (ray casting against it).

A navigator tells what its laser sees that the map does not explain (a person, a moving
object) by comparing each beam with the map. A point near a map obstacle looks explained by
it, but a beam that ends well short of where the map says it should is stopped by something
the map does not have: a person standing against a wall or a pillar, on the robot's side of
it. ``MapCaster`` answers that comparison with the laser model's own ray casting
(``rei.runtime.raycast.RayCaster``, the very step each scan takes), over the boxes and
cylinders of the map the robot was given.
This module must never import pybullet, and never read anything but that map.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from rei.runtime.raycast import RayCaster, ShapeSet
from rei.runtime.robot.contract import MapObstacle


class MapCaster:
    """Ray casting against the boxes and cylinders of a static map (immutable once built)."""

    def __init__(self, obstacles: Sequence[MapObstacle], grow: float = 0.0) -> None:
        """``grow``: metres every obstacle is cast as larger, so that a beam which grazes a
        corner exactly still hits it whatever the rounding of its direction."""
        boxes = np.array([(o.x, o.y, o.yaw, o.size_x / 2 + grow, o.size_y / 2 + grow)
                          for o in obstacles if o.shape != "cylinder"], dtype=float)
        circles = np.array([(o.x, o.y, o.radius + grow) for o in obstacles
                            if o.shape == "cylinder"], dtype=float)
        self._caster = RayCaster(ShapeSet(boxes.reshape(-1, 5), circles.reshape(-1, 3)))

    def ranges(self, origin: tuple[float, float], directions: np.ndarray,
               max_range: float) -> np.ndarray:
        """Distance (N,) from ``origin`` along each unit direction (N, 2; world frame) to the
        first map obstacle, ``inf`` beyond ``max_range``; 0 from inside an obstacle."""
        if not len(directions):
            return np.zeros(0)
        best = self._caster.cast(np.array(origin, dtype=float), directions, max_range)
        return np.where(best <= max_range, best, math.inf)
