"""Difficulty descriptors of a room and its mission: the five BARN metrics along the robot's
path (Perille, Truong, Xiao, Stone: "Benchmarking Metric Ground Navigation", SSRR 2020) and
crowd measures.

Everything is computed from geometry only — floor cells, the footprints of standing
objects, goals and trajectories — never from names, so renaming anything leaves the
descriptors unchanged. The inputs come from a generator's plan or from a parsed room
(``scene_of_documents``), so a user can describe hand-written rooms with the same numbers.

BARN computes its metrics on an occupancy grid along the path from start to goal; we
rasterise walls, cells outside the room and object footprints at ``RESOLUTION`` and walk
the shortest path of the inflated floor graph through the goals (and back to the first
goal when the mission has more than one cycle). See docs/rooms.md for the definitions.
This module must never write files or draw random numbers.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, fields, replace
from functools import lru_cache

import numpy as np

from rei.catalogue import Box, Cylinder, Footprint, Polygon
from rei.generators.rooms.geometry import Cell, catmull_rom, entries, fast_route

RESOLUTION = 0.1
"""Metres per occupancy cell (BARN's grids are of this order for a robot of ~0.5 m)."""
RAY_DIRECTIONS = 16
RAY_CAP = 3.5
"""Metres; the range of the TurtleBot3's LDS-01 laser, so 'visible' means 'the robot sees it'."""
PATH_STEP = 0.5
"""Metres between the path points where rays are cast."""


@dataclass(frozen=True)
class Obstacle:
    cell: Cell
    footprint: Footprint
    heading_deg: float


@dataclass(frozen=True)
class Scene:
    """What the descriptors see: geometry in the layout frame, no names."""

    tile: float
    floors: frozenset[Cell]
    obstacles: tuple[Obstacle, ...]
    goals: tuple[Cell, ...]
    cycles: int
    trajectories: tuple[tuple[tuple[Cell, ...], bool], ...]
    """Control vertices and loop flag of each human or moving object."""
    humans: int


@dataclass(frozen=True)
class Descriptors:
    closest_obstacle_m: float
    visibility_m: float
    dispersion: float
    characteristic_dimension_m: float
    tortuosity: float
    narrowest_m: float
    path_length_m: float
    human_count: int
    crossings: int
    object_density: float

    def as_row(self) -> dict[str, str]:
        return {f.name: format_number(getattr(self, f.name)) for f in fields(self)}


DESCRIPTOR_NAMES: tuple[str, ...] = tuple(f.name for f in fields(Descriptors))


class UnreachableGoals(ValueError):
    """The goals cannot be visited in order on the inflated floor graph."""


def format_number(value: float | int) -> str:
    if isinstance(value, int):
        return str(value)
    text = f"{value:.3f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


@lru_cache(maxsize=256)
def _footprint_mask(footprint: Footprint, heading_deg: float, sub: int, tile: float
                    ) -> np.ndarray:
    """Which of a tile's sub x sub occupancy cells the footprint covers (centre test)."""
    coords = (np.arange(sub) + 0.5) / sub * tile - tile / 2
    xs, ys = np.meshgrid(coords, -coords)  # rows run from the tile's top down
    if isinstance(footprint, Cylinder):
        return np.asarray((xs ** 2 + ys ** 2) <= footprint.radius ** 2)
    a = math.radians(heading_deg)
    c, s = math.cos(a), math.sin(a)
    u = c * xs + s * ys
    v = -s * xs + c * ys
    if isinstance(footprint, Box):
        hx, hy = footprint.half_extents()
    elif isinstance(footprint, Polygon):
        hx, hy = footprint.half_extents()
    else:
        hx = hy = tile / 2
    return np.asarray((np.abs(u) <= hx) & (np.abs(v) <= hy))


@lru_cache(maxsize=8)
def _ray_offsets(n_steps: int) -> tuple[np.ndarray, np.ndarray]:
    """(D, S) pixel offsets (rows down, columns right) of the samples of each ray."""
    angles = np.arange(RAY_DIRECTIONS) * (2 * math.pi / RAY_DIRECTIONS)
    k = np.arange(1, n_steps + 1)
    cols = np.rint(np.cos(angles)[:, None] * k[None, :]).astype(int)
    rows = np.rint(-np.sin(angles)[:, None] * k[None, :]).astype(int)
    return rows, cols


@dataclass(frozen=True)
class _Raster:
    occupied: np.ndarray
    sub: int
    res: float
    i0: int
    j1: int
    """Cell (i0, j1) is the top-left tile of the image."""

    def to_pixels(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Metric points (layout frame) -> (row, col) pixel indices (may be out of range)."""
        x = points[..., 0] - (self.i0 - 0.5) * self.res * self.sub
        y = (self.j1 + 0.5) * self.res * self.sub - points[..., 1]
        return np.floor(y / self.res).astype(int), np.floor(x / self.res).astype(int)


def _rasterise(scene: Scene) -> _Raster:
    sub = max(1, int(round(scene.tile / RESOLUTION)))
    res = scene.tile / sub
    i_values = [i for i, _ in scene.floors]
    j_values = [j for _, j in scene.floors]
    i0, i1 = min(i_values) - 1, max(i_values) + 1
    j0, j1 = min(j_values) - 1, max(j_values) + 1
    occupied = np.ones(((j1 - j0 + 1) * sub, (i1 - i0 + 1) * sub), dtype=bool)
    for i, j in scene.floors:
        r, c = (j1 - j) * sub, (i - i0) * sub
        occupied[r:r + sub, c:c + sub] = False
    for obstacle in scene.obstacles:
        i, j = obstacle.cell
        r, c = (j1 - j) * sub, (i - i0) * sub
        occupied[r:r + sub, c:c + sub] |= _footprint_mask(obstacle.footprint,
                                                          float(obstacle.heading_deg), sub,
                                                          scene.tile)
    return _Raster(occupied, sub, res, i0, j1)


def robot_route(scene: Scene) -> list[Cell]:
    """The robot's shortest route through the goals in order (and back for cycles > 1)."""
    # Searched in room-corner coordinates so that ties between equally short routes are
    # broken the same way in every frame.
    di = min(i for i, _ in scene.floors)
    dj = max(j for _, j in scene.floors)
    blocked = {(o.cell[0] - di, o.cell[1] - dj) for o in scene.obstacles}
    free = {(i - di, j - dj) for i, j in scene.floors} - blocked
    stops = list(scene.goals) + ([scene.goals[0]] if scene.cycles > 1 else [])
    cells = fast_route(free, [(i - di, j - dj) for i, j in stops])
    if cells is None:
        raise UnreachableGoals("goals are not reachable in order")
    return [(i + di, j + dj) for i, j in cells]


def _path_points(cells: Sequence[Cell], tile: float) -> tuple[np.ndarray, float]:
    pts = np.asarray(cells, dtype=float) * tile
    if len(pts) == 1:
        return pts, 0.0
    seg = np.diff(pts, axis=0)
    lengths = np.hypot(seg[:, 0], seg[:, 1])
    total = float(lengths.sum())
    s = np.concatenate([[0.0], np.cumsum(lengths)])
    at = np.arange(0.0, total + 1e-9, PATH_STEP)
    return np.stack([np.interp(at, s, pts[:, 0]), np.interp(at, s, pts[:, 1])], axis=1), total


def _normalised(scene: Scene, cells: list[Cell]) -> tuple[Scene, list[Cell]]:
    di = min(i for i, _ in scene.floors)
    dj = max(j for _, j in scene.floors)

    def shift(c: Cell) -> Cell:
        return (c[0] - di, c[1] - dj)

    moved = replace(
        scene,
        floors=frozenset(shift(c) for c in scene.floors),
        obstacles=tuple(replace(o, cell=shift(o.cell)) for o in scene.obstacles),
        goals=tuple(shift(c) for c in scene.goals),
        trajectories=tuple((tuple(shift(c) for c in v), loop)
                           for v, loop in scene.trajectories))
    return moved, [shift(c) for c in cells]


def describe(scene: Scene, route_cells: Sequence[Cell] | None = None) -> Descriptors:
    """The descriptors of one scene; ``route_cells`` when the caller already has the route."""
    cells = list(route_cells) if route_cells is not None else robot_route(scene)
    # Work in cells relative to the room's corner: the same room in another frame (a
    # generator's grid, a layout rooted at the robot) then gives bit-identical numbers.
    scene, cells = _normalised(scene, cells)
    raster = _rasterise(scene)
    points, length = _path_points(cells, scene.tile)
    occ = raster.occupied
    rows_n, cols_n = occ.shape

    # Rays: (P, D, S) samples of the occupancy grid, at whole-pixel offsets from the
    # point's pixel (within half a pixel of the exact ray), on an image padded with
    # occupied pixels so no sample falls outside.
    n_steps = int(round(RAY_CAP / raster.res))
    steps = np.arange(1, n_steps + 1) * raster.res
    off_r, off_c = _ray_offsets(n_steps)
    padded = np.pad(occ, n_steps + 1, constant_values=True)
    pr, pc = raster.to_pixels(points)
    pr = np.clip(pr, -n_steps, rows_n + n_steps) + n_steps + 1
    pc = np.clip(pc, -n_steps, cols_n + n_steps) + n_steps + 1
    hit = padded[pr[:, None, None] + off_r[None], pc[:, None, None] + off_c[None]]
    any_hit = hit.any(axis=2)
    first = np.argmax(hit, axis=2)
    rays = np.where(any_hit, steps[first], RAY_CAP)  # (P, D)

    visibility = float(rays.mean())
    dispersion = float((any_hit != np.roll(any_hit, 1, axis=1)).sum(axis=1).mean())
    half = RAY_DIRECTIONS // 2
    axes = rays[:, :half] + rays[:, half:]
    widths = axes.min(axis=1)

    # Distance to the closest obstacle: to the centres of occupied cells on an
    # occupied/free border, less half a cell (the border of the occupied cell).
    pad = np.pad(occ, 1, constant_values=True)
    free_next = ~(pad[:-2, 1:-1] & pad[2:, 1:-1] & pad[1:-1, :-2] & pad[1:-1, 2:])
    border_r, border_c = np.nonzero(occ & free_next)
    bx = (raster.i0 - 0.5) * raster.res * raster.sub + (border_c + 0.5) * raster.res
    by = (raster.j1 + 0.5) * raster.res * raster.sub - (border_r + 0.5) * raster.res
    if len(bx):
        px, py = points[:, 0:1].astype(np.float32), points[:, 1:2].astype(np.float32)
        bx32, by32 = bx.astype(np.float32)[None, :], by.astype(np.float32)[None, :]
        d = np.sqrt(((px - bx32) ** 2 + (py - by32) ** 2).min(axis=1).astype(float))
        closest = float(np.maximum(d - raster.res / 2, 0.0).mean())
    else:
        closest = RAY_CAP

    stops = list(scene.goals) + ([scene.goals[0]] if scene.cycles > 1 else [])
    legs = zip(stops[:-1], stops[1:], strict=True)
    straight = sum(math.dist(a, b) for a, b in legs) * scene.tile
    tortuosity = length / straight if straight > 0 else 1.0

    corridor = set(cells)
    crossings = 0
    for vertices, loop in scene.trajectories:
        spline = catmull_rom([(float(i), float(j)) for i, j in vertices], loop)
        crossings += entries(spline, corridor, loop)
    return Descriptors(
        closest_obstacle_m=closest,
        visibility_m=visibility,
        dispersion=dispersion,
        characteristic_dimension_m=float(widths.mean()),
        tortuosity=tortuosity,
        narrowest_m=float(widths.min()),
        path_length_m=length,
        human_count=scene.humans,
        crossings=crossings,
        object_density=len(scene.obstacles) / len(scene.floors) if scene.floors else 0.0,
    )


def scene_of_documents(room_doc: object, mission_doc: object) -> Scene:
    """The scene of a parsed, valid room and mission (rei.lang documents)."""
    from rei.lang.room.checks import blocking_objects

    room = room_doc.room  # type: ignore[attr-defined]
    layout = room_doc.layout  # type: ignore[attr-defined]
    catalogue = room_doc.catalogue  # type: ignore[attr-defined]
    mission = mission_doc.mission  # type: ignore[attr-defined]
    cells = layout.cells
    floors = frozenset(cells[n] for n in room.floors if n in cells)
    obstacles = tuple(
        Obstacle(cells[o.floor.name], catalogue.get(o.type).footprint, o.heading_deg or 0.0)
        for o in blocking_objects(room))
    moving = [o for o in room.objects if o.trajectory is not None]
    trajectories = tuple((tuple(cells[v.floor.name] for v in o.trajectory.vertices),
                          o.trajectory.loop) for o in moving)
    return Scene(
        tile=room.tile_size, floors=floors, obstacles=obstacles,
        goals=tuple(cells[g.floor.name] for g in mission.goals), cycles=mission.cycles,
        trajectories=trajectories, humans=sum(1 for o in room.objects if o.role == "human"))
