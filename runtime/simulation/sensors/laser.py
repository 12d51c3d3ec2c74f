"""A planar laser scanner, ray-cast in numpy against the world's footprints (thesis 9.1).

Each scan casts every beam at once (``rei.runtime.raycast``): for a 360-beam scan in a room
of walls this is an order of magnitude cheaper than ``rayTestBatch`` and gives the same
ranges (tests compare the two). Only bodies taller than the scan plane are seen. Ranges are
quantised to a millimetre, the resolution of the LDS-01 and most 2D scanners. This module
must never import pybullet.
"""

from __future__ import annotations

import math

import numpy as np

from rei.catalogue import LaserSpec
from rei.runtime.raycast import RayCaster, ShapeSet

RESOLUTION = 1e-3


class Laser2D:
    """Scans a fixed set of static shapes plus moving shapes given per scan."""

    def __init__(self, spec: LaserSpec, static: ShapeSet) -> None:
        self.spec = spec
        self.angle_min = -spec.fov / 2
        self.angle_increment = spec.fov / spec.beams
        self.angles = self.angle_min + self.angle_increment * np.arange(spec.beams)
        self.caster = RayCaster(static)

    def origin(self, pose: tuple[float, float, float]) -> np.ndarray:
        x, y, yaw = pose
        c, s = math.cos(yaw), math.sin(yaw)
        return np.array([x + c * self.spec.mount_x - s * self.spec.mount_y,
                         y + s * self.spec.mount_x + c * self.spec.mount_y])

    def scan(self, pose: tuple[float, float, float], moving: ShapeSet | None = None,
             rng: np.random.Generator | None = None, noise: float = 0.0) -> np.ndarray:
        """Ranges of every beam from the robot at ``pose`` (max_range where nothing is hit).

        With ``noise`` > 0, every range that hit something gets a Gaussian error of that
        standard deviation drawn from ``rng`` (the run's seeded generator), then is clipped
        to the sensor's limits, as a real scanner's readings are."""
        spec = self.spec
        o = self.origin(pose)
        world_angles = self.angles + pose[2]
        dirs = np.stack((np.cos(world_angles), np.sin(world_angles)), axis=1)
        reach = spec.max_range
        t = self.caster.cast(o, dirs, reach, moving)
        if noise > 0 and rng is not None:
            hit = t <= reach
            t = np.where(hit, t + rng.normal(0.0, noise, size=t.shape), t)
            t = np.where(hit, np.minimum(t, reach), t)
        ranges = np.where(t > reach, reach, np.maximum(t, spec.min_range))
        return np.round(ranges, 3)
