"""Where a human has room among the walls and fixed objects: the distance to the nearest
box, the walls a human touches, and whether (and where) it can step aside.

A box is a row of (x, y, yaw, half x, half y), as the animator's ``wall_boxes`` builds them.
Everything here is a pure function of positions; this module must never import pybullet or
the monitor, nor judge the robot.
"""

from __future__ import annotations

import math

import numpy as np

from rei.runtime.simulation.animator.agent import Vec


def wall_distance(walls: np.ndarray, x: float, y: float) -> float:
    """Distance from (x, y) to the nearest of the boxes ``walls`` (rows of x, y, yaw, half
    x, half y); inf when there are none."""
    if not len(walls):
        return math.inf
    ex, ey, _, _ = _to_nearest(walls, x, y)
    return float(np.hypot(ex, ey).min())


def wall_normals(walls: np.ndarray, x: float, y: float, reach: float) -> list[Vec]:
    """Unit vectors from (x, y) towards the nearest point of each of the boxes ``walls`` (as
    in ``wall_distance``) within ``reach`` of it: the walls a human there touches."""
    if not len(walls):
        return []
    ex, ey, c, s = _to_nearest(walls, x, y)
    dist = np.hypot(ex, ey)
    near = (dist <= reach) & (dist > 1e-9)
    wx, wy = c * ex - s * ey, s * ex + c * ey  # in the world's frame
    return [(float(wx[i] / dist[i]), float(wy[i] / dist[i])) for i in np.flatnonzero(near)]


def _to_nearest(walls: np.ndarray, x: float, y: float
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """From (x, y) to the nearest point of each box ``walls`` (as in ``wall_distance``), in
    the box's frame (zero from inside it), with the cosine and sine of each box's yaw."""
    c, s = np.cos(walls[:, 2]), np.sin(walls[:, 2])
    dx, dy = x - walls[:, 0], y - walls[:, 1]
    lx, ly = c * dx + s * dy, -s * dx + c * dy
    return (np.clip(lx, -walls[:, 3], walls[:, 3]) - lx,
            np.clip(ly, -walls[:, 4], walls[:, 4]) - ly, c, s)


def room_aside(walls: np.ndarray, x: float, y: float, radius: float, direction: Vec,
               reach: float) -> bool:
    """Whether a human at (x, y) has room to step ``reach`` metres along ``direction`` (unit
    length): the place there keeps its radius from every wall (``walls`` as in
    ``wall_distance``)."""
    return wall_distance(walls, x + direction[0] * reach, y + direction[1] * reach) >= radius


def way_aside(walls: np.ndarray, x: float, y: float, radius: float, across: Vec, away: Vec,
              reach: float) -> Vec | None:
    """Where a human at (x, y) giving way steps (a unit direction), None where it has no
    room: ``across`` the robot's heading if it has room there (``room_aside``), else the
    first with room of straight ``away`` from the robot and away turned 45 and then 90
    degrees either way (never towards the robot). ``reach`` 0: ``across``, unlooked."""
    if reach <= 0.0:
        return across
    candidates = [across, away]
    for turn in (math.pi / 4.0, -math.pi / 4.0, math.pi / 2.0, -math.pi / 2.0):
        c, s = math.cos(turn), math.sin(turn)
        candidates.append((c * away[0] - s * away[1], s * away[0] + c * away[1]))
    for direction in candidates:
        if room_aside(walls, x, y, radius, direction, reach):
            return direction
    return None
