"""Exact footprint distances from the robot to every observed object, vectorised with numpy.

Footprints are convex or simple polygons (boxes become four corners) or circles. The
distance is between the shapes, not their centres: the smallest boundary-to-boundary
distance when apart, and 0 or negative when they overlap (minus that boundary distance
when one shape reaches into the other). Objects whose centres are so far away that no
threshold of the specification can be crossed get a cheap lower bound instead (the broad
phase), which decides every comparison against those thresholds the same way. This
module must never import the simulator or keep state between calls.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from rei.catalogue import Box, Cylinder, Footprint, Polygon, Tile

FloatArray = np.ndarray


def local_shape(footprint: Footprint, tile: float) -> tuple[np.ndarray | None, float]:
    """(polygon vertices (K, 2) counter-clockwise, or None for a circle, circle radius)."""
    if isinstance(footprint, Tile):
        footprint = Box(tile, tile)
    if isinstance(footprint, Box):
        hx, hy = footprint.size_x / 2, footprint.size_y / 2
        return np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]], dtype=np.float64), 0.0
    if isinstance(footprint, Cylinder):
        return None, float(footprint.radius)
    if isinstance(footprint, Polygon):
        return np.array(footprint.points, dtype=np.float64), 0.0
    raise TypeError(f"unknown footprint {footprint!r}")


def _transform(local: np.ndarray, poses: np.ndarray) -> np.ndarray:
    """World vertices (N, K, 2) of local polygons (N, K, 2) placed at poses (N, 3)."""
    c = np.cos(poses[:, 2])[:, None]
    s = np.sin(poses[:, 2])[:, None]
    x = local[..., 0]
    y = local[..., 1]
    return np.stack((c * x - s * y + poses[:, 0:1], s * x + c * y + poses[:, 1:2]), axis=-1)


def _point_segment(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distances from points p to segments a-b (broadcast over leading axes)."""
    ab = b - a
    ap = p - a
    denom = np.einsum("...i,...i->...", ab, ab)
    t = np.einsum("...i,...i->...", ap, ab) / np.where(denom > 0, denom, 1.0)
    t = np.clip(t, 0.0, 1.0)
    closest = a + t[..., None] * ab
    d = p - closest
    return np.sqrt(np.einsum("...i,...i->...", d, d))


def _cross(o: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return (a[..., 0] - o[..., 0]) * (b[..., 1] - o[..., 1]) - (a[..., 1] - o[..., 1]) * (
        b[..., 0] - o[..., 0])


def _inside(points: np.ndarray, poly: np.ndarray, poly_next: np.ndarray) -> np.ndarray:
    """Crossing-number test: points (..., 2) inside polygons with edges poly->poly_next
    (..., K, 2); leading axes broadcast; returns (...)."""
    px = points[..., None, 0]
    py = points[..., None, 1]
    x1, y1 = poly[..., 0], poly[..., 1]
    x2, y2 = poly_next[..., 0], poly_next[..., 1]
    straddles = (y1 > py) != (y2 > py)
    dy = np.where(y2 != y1, y2 - y1, 1.0)
    x_at = x1 + (py - y1) * (x2 - x1) / dy
    crossings = np.count_nonzero(straddles & (px < x_at), axis=-1)
    return (crossings % 2) == 1


@dataclass(frozen=True)
class FootprintSet:
    """The robot's and every observed object's footprint, prepared once per run."""

    robot_polygon: np.ndarray | None
    robot_radius: float
    poly_index: np.ndarray
    """Indices (into the header's objects) of polygon footprints."""
    poly_local: np.ndarray
    """(P, K, 2) local vertices, padded by repeating the last vertex."""
    circle_index: np.ndarray
    circle_radius: np.ndarray
    bound_radius: np.ndarray = field(repr=False)
    """(N,) circumradius of every object (broad phase)."""
    robot_bound: float = 0.0
    count: int = 0

    @staticmethod
    def build(robot: Footprint, objects: list[Footprint], tile: float) -> FootprintSet:
        rpoly, rrad = local_shape(robot, tile)
        polys: list[np.ndarray] = []
        pidx: list[int] = []
        cidx: list[int] = []
        crad: list[float] = []
        bound = np.zeros(len(objects))
        for i, fp in enumerate(objects):
            poly, radius = local_shape(fp, tile)
            if poly is None:
                cidx.append(i)
                crad.append(radius)
                bound[i] = radius
            else:
                pidx.append(i)
                polys.append(poly)
                bound[i] = float(np.max(np.hypot(poly[:, 0], poly[:, 1])))
        k = max((len(p) for p in polys), default=1)
        padded = np.zeros((len(polys), k, 2))
        for j, p in enumerate(polys):
            padded[j, : len(p)] = p
            padded[j, len(p):] = p[-1]
        robot_bound = rrad if rpoly is None else float(np.max(np.hypot(rpoly[:, 0],
                                                                        rpoly[:, 1])))
        return FootprintSet(rpoly, rrad, np.array(pidx, dtype=np.intp), padded,
                            np.array(cidx, dtype=np.intp), np.array(crad), bound, robot_bound,
                            len(objects))

    def robot_inradius(self) -> float:
        if self.robot_polygon is None:
            return self.robot_radius
        p = self.robot_polygon
        q = np.roll(p, -1, axis=0)
        return float(np.min(_point_segment(np.zeros(2), p, q)))

    def distances(self, robot_pose: tuple[float, float, float], poses: np.ndarray,
                  cutoff: float = math.inf) -> np.ndarray:
        """(N,) robot-to-object footprint distances; beyond ``cutoff`` a lower bound."""
        out = np.empty(self.count)
        if self.count == 0:
            return out
        rx, ry, ryaw = robot_pose
        centre = np.hypot(poses[:, 0] - rx, poses[:, 1] - ry)
        lower = centre - self.bound_radius - self.robot_bound
        out[:] = lower
        rp = np.array(robot_pose, dtype=np.float64)[None, :]
        robot_world = None if self.robot_polygon is None else _transform(
            self.robot_polygon[None], rp)[0]
        if len(self.circle_index):
            ci = self.circle_index
            out[ci] = self._to_circles(robot_world, (rx, ry), poses[ci, :2], self.circle_radius)
        if len(self.poly_index):
            near = self.poly_index[lower[self.poly_index] <= cutoff]
            if len(near):
                sel = np.searchsorted(self.poly_index, near)
                world = _transform(self.poly_local[sel], poses[near])
                out[near] = self._to_polygons(robot_world, (rx, ry), world)
        return out

    def _to_circles(self, robot_world: np.ndarray | None, centre: tuple[float, float],
                    centres: np.ndarray, radii: np.ndarray) -> np.ndarray:
        if robot_world is None:
            return np.hypot(centres[:, 0] - centre[0], centres[:, 1] - centre[1]) - (
                radii + self.robot_radius)
        a = robot_world[None, :, :]
        b = np.roll(robot_world, -1, axis=0)[None, :, :]
        boundary = _point_segment(centres[:, None, :], a, b).min(axis=1)
        inside = _inside(centres, robot_world[None], np.roll(robot_world, -1, axis=0)[None])
        return np.where(inside, -boundary - radii, boundary - radii)

    def _to_polygons(self, robot_world: np.ndarray | None, centre: tuple[float, float],
                     world: np.ndarray) -> np.ndarray:
        nxt = np.roll(world, -1, axis=1)
        if robot_world is None:
            c = np.array(centre)
            boundary = _point_segment(c[None, None, :], world, nxt).min(axis=1)
            inside = _inside(np.broadcast_to(c, (len(world), 2)), world, nxt)
            return np.where(inside, -boundary - self.robot_radius,
                            boundary - self.robot_radius)
        r = robot_world
        rn = np.roll(r, -1, axis=0)
        # object vertices against robot edges, robot vertices against object edges
        d1 = _point_segment(world[:, :, None, :], r[None, None], rn[None, None])
        d2 = _point_segment(r[None, None, :, :], world[:, :, None, :], nxt[:, :, None, :])
        boundary = np.minimum(d1.min(axis=(1, 2)), d2.min(axis=(1, 2)))
        # proper edge crossings
        a, b = world[:, :, None, :], nxt[:, :, None, :]
        c, d = r[None, None, :, :], rn[None, None, :, :]
        o1, o2 = _cross(a, b, c), _cross(a, b, d)
        o3, o4 = _cross(c, d, a), _cross(c, d, b)
        crossing = (((o1 > 0) & (o2 < 0)) | ((o1 < 0) & (o2 > 0))) & (
            ((o3 > 0) & (o4 < 0)) | ((o3 < 0) & (o4 > 0)))
        overlap = crossing.any(axis=(1, 2))
        overlap |= _inside(np.broadcast_to(r[0], (len(world), 2)), world, nxt)
        overlap |= _inside(world[:, 0, :], r[None], rn[None])
        return np.where(overlap, -boundary, boundary)
