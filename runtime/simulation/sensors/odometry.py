"""Odometry: the pose and twist the robot believes, integrated from its measured motion.

Without drift the belief follows the ground truth exactly. With drift (``drift`` > 0) every
update scales the travelled distance and turn by a random factor drawn from the run's seeded
generator, so the belief wanders the way wheel odometry does; the same seed gives the same
wander. This module must never read the simulator: it is fed the motion.
"""

from __future__ import annotations

import math

import numpy as np


class Odometry:
    def __init__(self, start: tuple[float, float, float], drift: float,
                 rng: np.random.Generator) -> None:
        self.drift = drift
        self.rng = rng
        self.pose = start
        self.twist = (0.0, 0.0)
        self._last_truth = start

    def update(self, truth: tuple[float, float, float], dt: float) -> None:
        """Advance the belief by the robot's motion since the previous update."""
        lx, ly, lyaw = self._last_truth
        x, y, yaw = truth
        self._last_truth = truth
        # Motion in the robot's previous frame: forward distance and turn.
        c, s = math.cos(lyaw), math.sin(lyaw)
        fwd = c * (x - lx) + s * (y - ly)
        side = -s * (x - lx) + c * (y - ly)
        turn = math.remainder(yaw - lyaw, math.tau)
        if self.drift > 0.0:
            noise = self.rng.normal(0.0, self.drift, size=2)
            fwd *= 1.0 + noise[0]
            side *= 1.0 + noise[0]
            turn *= 1.0 + noise[1]
            bx, by, byaw = self.pose
            cb, sb = math.cos(byaw), math.sin(byaw)
            self.pose = (bx + cb * fwd - sb * side, by + sb * fwd + cb * side,
                         math.remainder(byaw + turn, math.tau))
        else:
            self.pose = truth
        self.twist = (fwd / dt, turn / dt) if dt > 0 else (0.0, 0.0)
