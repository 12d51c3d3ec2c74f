"""The animator: moves humans and dynamic objects along splines by velocity (thesis 4.2.2, 6.2.2).

Each physics step sets the body's planar velocity to the spline's displacement over the step,
(r(t + dt) - r(t)) / dt, plus a bounded pull back towards r(t) so a body that was pushed or
held up by a contact (the robot, a wall) rejoins its path instead of walking a parallel one.
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


@dataclass(frozen=True)
class Animated:
    body: int
    """The body's id in the world."""
    spline: CatmullRom
    face_motion: bool


def spline_of(trajectory: Trajectory) -> CatmullRom:
    pts = np.array(trajectory.points, dtype=float)
    return CatmullRom(pts[:, 0], pts[:, 1:3], trajectory.loop)


def planar_command(item: Animated, time: float, dt: float,
                   pose: tuple[float, float, float]) -> tuple[float, float, float]:
    """(vx, vy, wz) that moves the body along its spline from ``time`` to ``time + dt``."""
    x0, y0 = item.spline.position(time)
    x1, y1 = item.spline.position(time + dt)
    vx, vy = (x1 - x0) / dt, (y1 - y0) / dt
    ex, ey = x0 - pose[0], y0 - pose[1]
    err = math.hypot(ex, ey)
    if err > 1e-9:
        pull = min(CATCH_UP_GAIN * err, MAX_CATCH_UP) / err
        vx += ex * pull
        vy += ey * pull
    wz = 0.0
    if item.face_motion and math.hypot(x1 - x0, y1 - y0) > 1e-6:
        heading = math.atan2(y1 - y0, x1 - x0)
        wz = math.remainder(heading - pose[2], math.tau) / TURN_TIME
    return vx, vy, wz
