"""Laser clearance: how far what the laser saw is from the robot's own footprint boundary.

A range is measured from the laser's mount point, which need not be the footprint's centre
(the TurtleBot3 Waffle's sits 6.4 cm behind it), so ``laser_min - inradius`` misjudges a
touch in front (issue 6). Here each beam gets the distance ``edge_i`` from the mount point
along the beam to the footprint boundary, computed once per scan geometry, and a scan's
clearance is ``min_i (range_i - edge_i)`` over the beams that hit something. This module
must never import the simulator or keep module-level state.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from rei.catalogue import Footprint
from rei.runtime.messages import LaserScan
from rei.runtime.observation.model.geometry import inside_polygon, local_shape

_PARALLEL = 1e-12
"""A beam and a polygon side closer than this to parallel never cross (cross product)."""


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.asarray(a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0])


def _inside_polygon(point: np.ndarray, poly: np.ndarray) -> bool:
    """Strictly inside a simple polygon (even-odd rule; a point on a side is not inside)."""
    a, b = poly, np.roll(poly, -1, axis=0)
    e = b - a
    rel = point - a
    on_side = (np.abs(_cross(e, rel)) <= 1e-12) & ((rel * e).sum(axis=1) >= 0) & (
        (rel * e).sum(axis=1) <= (e * e).sum(axis=1))
    if bool(on_side.any()):
        return False
    return bool(inside_polygon(point, a, b))


def beam_edges(footprint: Footprint, mount: Sequence[float], angles: np.ndarray) -> np.ndarray:
    """(N,) distance from ``mount`` (robot frame) along each beam angle (radians from the
    robot's heading) to the footprint's boundary: where the robot ends in that direction.
    A mount on or outside the footprint gets 0 for every beam (its ranges are clearances)."""
    angles = np.asarray(angles, dtype=np.float64)
    m = np.asarray(mount, dtype=np.float64)[:2]
    dirs = np.stack((np.cos(angles), np.sin(angles)), axis=1)
    poly, radius = local_shape(footprint, 0.0)
    if poly is None:
        inside = float(m @ m) < radius * radius
        if not inside:
            return np.zeros(len(angles))
        b = dirs @ m
        return np.asarray(-b + np.sqrt(b * b - (float(m @ m) - radius * radius)))
    if not _inside_polygon(m, poly):
        return np.zeros(len(angles))
    a = poly
    e = np.roll(poly, -1, axis=0) - a  # (K, 2) sides
    rel = a - m  # (K, 2)
    denom = _cross(dirs[:, None, :], e[None, :, :])  # (N, K)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = _cross(rel[None, :, :], e[None, :, :]) / denom
        u = _cross(rel[None, :, :], dirs[:, None, :]) / denom
    hit = (np.abs(denom) > _PARALLEL) & (u >= -1e-12) & (u <= 1 + 1e-12) & (t > 0)
    # From inside, the first side a beam crosses is where the footprint ends.
    edges = np.where(hit, t, np.inf).min(axis=1)
    return np.where(np.isfinite(edges), edges, 0.0)


def beam_angles(scan: LaserScan) -> np.ndarray:
    """The scan's beam angles in the robot's frame (the laser is mounted facing forward)."""
    return np.asarray(scan.angle_min + scan.angle_increment * np.arange(len(scan.ranges)))


def clearance(scan: LaserScan, edges: np.ndarray) -> float:
    """``min_i (range_i - edge_i)`` over the beams that hit something (a range below
    range_max); ``range_max`` when nothing was hit, as ``laser_min`` reads then."""
    ranges = np.asarray(scan.ranges, dtype=np.float64)
    # NaN beams compare false: no hit (NaN and inf arithmetic raise no warning); a hit's
    # clearance is finite, so inf means none
    nearest = float(np.where(ranges < scan.range_max, ranges - edges, np.inf).min())
    return float(scan.range_max) if nearest == math.inf else nearest


class BeamEdges:
    """The edges of one run's scans, recomputed only when the scan geometry changes."""

    def __init__(self, footprint: Footprint, mount: Sequence[float]) -> None:
        self.footprint = footprint
        self.mount = (float(mount[0]), float(mount[1]))
        self._key: tuple[float, float, int] | None = None
        self._edges = np.zeros(0)

    def of(self, scan: LaserScan) -> np.ndarray:
        key = (scan.angle_min, scan.angle_increment, len(scan.ranges))
        if key != self._key:
            self._edges = beam_edges(self.footprint, self.mount, beam_angles(scan))
            self._key = key
        return self._edges
