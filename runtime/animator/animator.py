"""The animator: moves humans and dynamic objects along splines by velocity (thesis 4.2.2, 6.2.2).

Each physics step sets the body's planar velocity to the spline's displacement over the step,
(r(t + dt) - r(t)) / dt, plus a bounded pull back towards r(t) (refreshed at the control rate)
so a body that was pushed or held up by a contact (the robot, a wall) rejoins its path
instead of walking a parallel one.
The body is never teleported, so collisions with the robot are real contacts. Humans turn to
face their direction of motion. Loops repeat; open trajectories stop at their last vertex.
This module must never decide anything about the robot or the mission.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rei.runtime.animator.spline import CatmullRom
from rei.runtime.world.manifest import Trajectory

CATCH_UP_GAIN = 1.0
"""1/s: how fast a displaced body returns to its path."""
MAX_CATCH_UP = 0.5
"""m/s added at most on top of the path's own speed."""
TURN_TIME = 0.5
"""s: time constant of a human turning towards where it walks."""
BLOCK = 1000
"""Physics steps whose curve displacements are computed together."""


@dataclass(frozen=True)
class Animated:
    body: int
    """The body's id in the world."""
    spline: CatmullRom
    face_motion: bool


def spline_of(trajectory: Trajectory) -> CatmullRom:
    pts = np.array(trajectory.points, dtype=float)
    return CatmullRom(pts[:, 0], pts[:, 1:3], trajectory.loop)


class Animator:
    """Drives every animated body: the curve's displacement each physics step, plus a pull
    back to the curve and a turn towards the walking direction, refreshed at the control rate.

    The curve's displacements are evaluated for a block of steps at once (vectorised), so a
    physics step only looks its velocity up; the feedback, which only needs to be stable, runs
    at the control rate.
    """

    def __init__(self, items: list[Animated], physics_rate: float) -> None:
        self.items = items
        self.rate = physics_rate
        self._feedback = [(0.0, 0.0, 0.0)] * len(items)
        self._block: int | None = None
        self._steps: list[tuple[list[float], list[float]]] = []

    def correct(self, step: int, poses: list[tuple[float, float, float]]) -> None:
        """Refresh each body's pull back to its curve from its ground-truth pose."""
        time = step / self.rate
        for k, (item, pose) in enumerate(zip(self.items, poses, strict=True)):
            x0, y0 = item.spline.position(time)
            ex, ey = x0 - pose[0], y0 - pose[1]
            err = math.hypot(ex, ey)
            cx = cy = 0.0
            if err > 1e-9:
                pull = min(CATCH_UP_GAIN * err, MAX_CATCH_UP) / err
                cx, cy = ex * pull, ey * pull
            wz = 0.0
            vx, vy = item.spline.velocity(time)
            if item.face_motion and math.hypot(vx, vy) > 1e-3:
                wz = math.remainder(math.atan2(vy, vx) - pose[2], math.tau) / TURN_TIME
            self._feedback[k] = (cx, cy, wz)

    def commands(self, step: int) -> list[tuple[int, float, float, float]]:
        """(body, vx, vy, wz) moving each body along its curve from ``step`` to ``step + 1``."""
        block, j = divmod(step, BLOCK)
        if self._block != block:
            self._fill(block)
        out = []
        for k, item in enumerate(self.items):
            cx, cy, wz = self._feedback[k]
            vx, vy = self._steps[k]
            out.append((item.body, vx[j] + cx, vy[j] + cy, wz))
        return out

    def _fill(self, block: int) -> None:
        """The curve's per-step displacements of a block of steps, for every body at once."""
        steps = block * BLOCK + np.arange(BLOCK + 1)
        times = steps / self.rate
        self._steps = []
        for item in self.items:
            moves = np.diff(item.spline.positions(times), axis=0) * self.rate
            self._steps.append((moves[:, 0].tolist(), moves[:, 1].tolist()))
        self._block = block
