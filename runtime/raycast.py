"""Ray casting in numpy against boxes and circles: the one step both the simulated laser
(rei.runtime.simulation.sensors.laser) and a navigator comparing a scan with its map
(rei.runtime.robot.navigator.mapcast) take, so neither side imports the other.

Each cast tests every beam against the boxes and cylinders within reach at once (broadcast
over beams x shapes), instead of one pybullet ray per beam. Wall tiles are merged into runs
along x so a room's boundary is a handful of boxes. A contract of runtime/'s root: it reads
the world manifest's records and imports nothing else of REI's; it must never import
pybullet or the simulation.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import cast

import numpy as np

from rei.catalogue import Box, Cylinder
from rei.runtime.artifacts.world import BodySpec, WorldManifest


@dataclass(frozen=True)
class ShapeSet:
    """Boxes (cx, cy, yaw, hx, hy) and circles (cx, cy, r), as arrays."""

    boxes: np.ndarray
    circles: np.ndarray


def merge_wall_tiles(walls: tuple[BodySpec, ...], tile: float) -> np.ndarray:
    """Wall tiles merged into boxes (cx, cy, 0, hx, hy), one per run of adjacent tiles along x."""
    rows: dict[int, list[int]] = {}
    for w in walls:
        rows.setdefault(round(w.y / tile), []).append(round(w.x / tile))
    boxes = []
    for j in sorted(rows):
        cells = sorted(set(rows[j]))
        start = prev = cells[0]
        for i in [*cells[1:], None]:
            if i is not None and i == prev + 1:
                prev = i
                continue
            boxes.append(((start + prev) / 2 * tile, j * tile, 0.0,
                          (prev - start + 1) * tile / 2, tile / 2))
            if i is not None:
                start = prev = i
    return np.array(boxes, dtype=float).reshape(-1, 5)


def shapes_of(bodies: list[BodySpec], poses: np.ndarray) -> ShapeSet:
    """Boxes and circles of bodies at the given (N, 3) poses."""
    boxes, circles = [], []
    for body, (x, y, yaw) in zip(bodies, poses, strict=False):
        fp = body.footprint
        if isinstance(fp, Cylinder):
            circles.append((x, y, fp.radius))
        elif isinstance(fp, Box):
            boxes.append((x, y, yaw, fp.size_x / 2, fp.size_y / 2))
    return ShapeSet(np.array(boxes, dtype=float).reshape(-1, 5),
                    np.array(circles, dtype=float).reshape(-1, 3))


def scene_shapes(manifest: WorldManifest, bodies: Sequence[BodySpec]) -> ShapeSet:
    """What the scan plane cuts of a room, as one fixed shape set: its walls (tiles merged)
    and those of ``bodies`` taller than the plane, at their poses in the manifest."""
    plane = manifest.laser.mount_z
    walls = merge_wall_tiles(tuple(w for w in manifest.walls if w.height > plane),
                             manifest.tile_size)
    seen = [b for b in bodies if b.height > plane]
    shapes = shapes_of(seen, np.array([(b.x, b.y, b.yaw) for b in seen]).reshape(-1, 3))
    return ShapeSet(np.concatenate((walls, shapes.boxes)), shapes.circles)


def ray_boxes(origin: np.ndarray, dirs: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """(N,) nearest hit distance of each ray against (M, 5) boxes; inf where none."""
    if len(boxes) == 0:
        return np.full(len(dirs), np.inf)
    c, s = np.cos(boxes[:, 2]), np.sin(boxes[:, 2])
    rel = origin[None, :] - boxes[:, :2]
    ox = c * rel[:, 0] + s * rel[:, 1]
    oy = -s * rel[:, 0] + c * rel[:, 1]
    dx = c[:, None] * dirs[None, :, 0] + s[:, None] * dirs[None, :, 1]
    dy = -s[:, None] * dirs[None, :, 0] + c[:, None] * dirs[None, :, 1]
    dx = np.where(np.abs(dx) < 1e-12, 1e-12, dx)
    dy = np.where(np.abs(dy) < 1e-12, 1e-12, dy)
    hx, hy = boxes[:, 3:4], boxes[:, 4:5]
    tx1 = (-hx - ox[:, None]) / dx
    tx2 = (hx - ox[:, None]) / dx
    ty1 = (-hy - oy[:, None]) / dy
    ty2 = (hy - oy[:, None]) / dy
    near = np.maximum(np.minimum(tx1, tx2), np.minimum(ty1, ty2))
    far = np.minimum(np.maximum(tx1, tx2), np.maximum(ty1, ty2))
    # An origin inside a box (the robot pressed into it) reads 0: the scanner is blinded.
    t = np.where(far >= np.maximum(near, 0.0), np.maximum(near, 0.0), np.inf)
    return cast(np.ndarray, t.min(axis=0))


def ray_circles(origin: np.ndarray, dirs: np.ndarray, circles: np.ndarray) -> np.ndarray:
    if len(circles) == 0:
        return np.full(len(dirs), np.inf)
    rel = origin[None, :] - circles[:, :2]
    b = rel @ dirs.T
    cc = (rel * rel).sum(axis=1) - circles[:, 2] ** 2
    disc = b * b - cc[:, None]
    root = np.sqrt(np.maximum(disc, 0.0))
    t = np.where(disc >= 0, -b - root, np.inf)
    t = np.where((disc >= 0) & (t < 0) & (-b + root >= 0), 0.0, t)
    t = np.where(t < 0, np.inf, t)
    return cast(np.ndarray, t.min(axis=0))


class RayCaster:
    """Ray casting against a fixed set of shapes (immutable once built): the one step both the
    laser model and a navigator's comparison with its map (rei.runtime.robot.navigator.mapcast)
    take."""

    def __init__(self, shapes: ShapeSet) -> None:
        self.shapes = shapes
        self._box_radius = np.hypot(shapes.boxes[:, 3], shapes.boxes[:, 4])

    def cast(self, origin: np.ndarray, dirs: np.ndarray, reach: float,
             moving: ShapeSet | None = None) -> np.ndarray:
        """(N,) distance from ``origin`` along each unit direction (N, 2; world frame) to the
        first shape hit, ``inf`` where none is; 0 from inside a shape. Every distance up to
        ``reach`` is exact; beyond it a shape may be left out (it may read ``inf``).

        Only the fixed shapes a beam of ``reach`` can touch are cast (a room has hundreds of
        wall tiles): those whose bounding circle comes within ``reach``, boundary included,
        so a shape touched at exactly ``reach`` is a hit at ``reach``. ``moving`` shapes
        (given per cast) are all cast."""
        boxes, circles = self.shapes.boxes, self.shapes.circles
        near = np.hypot(boxes[:, 0] - origin[0], boxes[:, 1] - origin[1]) \
            - self._box_radius <= reach
        cnear = np.hypot(circles[:, 0] - origin[0], circles[:, 1] - origin[1]) \
            - circles[:, 2] <= reach
        box_sets, circle_sets = [boxes[near]], [circles[cnear]]
        if moving is not None:
            box_sets.append(moving.boxes)
            circle_sets.append(moving.circles)
        return cast(np.ndarray, np.minimum(ray_boxes(origin, dirs, np.concatenate(box_sets)),
                                           ray_circles(origin, dirs,
                                                       np.concatenate(circle_sets))))
