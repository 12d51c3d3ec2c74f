"""Geometry the `reference` navigator shares between its parts: the signed distance to an
oriented box, and the distance-to-map field built from it.
This module must never import pybullet.
"""

from __future__ import annotations

import math

import numpy as np

from rei.runtime.robot.contract import ControllerContext


def box_distance(dx: np.ndarray, dy: np.ndarray, c: np.ndarray | float, s: np.ndarray | float,
                 hx: float, hy: float) -> np.ndarray:
    """Signed distance from points to an oriented box, negative inside: ``dx``, ``dy`` are the
    points' offsets from the box's centre, ``c``, ``s`` the cosine and sine of its yaw (scalars
    or arrays broadcast against the offsets), ``hx``, ``hy`` its half sizes. The operations
    and their order are those of each place it serves (the static map's field below, the
    roll-outs' swept-distance map, ``recovery.footprint_gaps``), so they compute the same bits
    as before; the dtype is the inputs' (float32 for the swept-distance map). The slow
    zone's gap (``LaserView._in_slow_zone``) differs: unsigned, and to the robot's own
    unrotated footprint, so it keeps its own operations.

    The monitor (``rei.runtime.observation.model.geometry``) keeps its own oriented-box
    distance on purpose, so the judge and the judged cannot share a bug.
    """
    qx = np.abs(c * dx + s * dy) - hx
    qy = np.abs(-s * dx + c * dy) - hy
    gaps: np.ndarray = (np.hypot(np.maximum(qx, 0), np.maximum(qy, 0))
                        + np.minimum(np.maximum(qx, qy), 0))
    return gaps


def clearance_field(xs: np.ndarray, ys: np.ndarray, ctx: ControllerContext,
                    reach: float) -> np.ndarray:
    """Distance from each grid point (xs[i], ys[j]) to the nearest obstacle of the static map.

    Each obstacle only updates the cells within ``reach`` of its bounding circle, so the cost
    grows with the number of obstacles, not with obstacles x cells; beyond ``reach`` the
    field holds ``reach`` (far enough for every use).
    """
    best = np.full((len(xs), len(ys)), reach)
    res_x = xs[1] - xs[0] if len(xs) > 1 else 1.0
    res_y = ys[1] - ys[0] if len(ys) > 1 else 1.0
    for ob in ctx.obstacles:
        r = (ob.radius if ob.shape == "cylinder" else math.hypot(ob.size_x, ob.size_y) / 2) + reach
        i0 = max(int((ob.x - r - xs[0]) / res_x), 0)
        i1 = min(int((ob.x + r - xs[0]) / res_x) + 2, len(xs))
        j0 = max(int((ob.y - r - ys[0]) / res_y), 0)
        j1 = min(int((ob.y + r - ys[0]) / res_y) + 2, len(ys))
        if i0 >= i1 or j0 >= j1:
            continue
        rx = xs[i0:i1, None] - ob.x
        ry = ys[None, j0:j1] - ob.y
        if ob.shape == "cylinder":
            d = np.hypot(rx, ry) - ob.radius
        else:
            d = box_distance(rx, ry, math.cos(ob.yaw), math.sin(ob.yaw), ob.size_x / 2,
                             ob.size_y / 2)
        np.minimum(best[i0:i1, j0:j1], d, out=best[i0:i1, j0:j1])
    return best
