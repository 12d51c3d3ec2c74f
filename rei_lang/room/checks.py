"""Room rules that need the catalogue or the layout: types, sizes, overlaps, reachability,
and the curves moving bodies walk."""

from __future__ import annotations

import math
from typing import cast

import networkx as nx
import numpy as np

from rei.catalogue import Catalogue, ObjectType, Tile
from rei.lang.errors import Diagnostic
from rei.lang.room.layout import Layout
from rei.lang.room.model import PlacedObject, Room
from rei.lang.room.motion import vertex_point, walkable
from rei.lang.room.spline import CatmullRom, vertex_times, walked_path
from rei.lang.suggest import did_you_mean

ROLE_KIND = {"static": "static", "dynamic": "dynamic", "human": "human", "robot": "robot"}
_FIT_SLACK = 1e-9


def rotated_half_extents(otype: ObjectType, heading_deg: float | None) -> tuple[float, float]:
    hx, hy = otype.footprint.half_extents()
    a = math.radians(heading_deg or 0.0)
    c, s = abs(math.cos(a)), abs(math.sin(a))
    return c * hx + s * hy, s * hx + c * hy


def offset_problem(offset: tuple[float, float], tile: float, half_x: float,
                   half_y: float | None = None) -> str:
    """'' when a body of half extents (half_x, half_y) moved ``offset`` from its floor's
    centre stays on that tile, else what was expected and found (for a diagnostic)."""
    dx, dy = offset
    hy = half_x if half_y is None else half_y
    room_x, room_y = tile / 2 - half_x, tile / 2 - hy
    if abs(dx) <= room_x + _FIT_SLACK and abs(dy) <= room_y + _FIT_SLACK:
        return ""
    what = "a point" if half_x == 0 and hy == 0 else \
        f"a footprint {2 * half_x:.2f} x {2 * hy:.2f} m"
    return (f"an offset keeping {what} on its {tile:g} m tile (at most {max(room_x, 0):.3g} m "
            f"in x and {max(room_y, 0):.3g} m in y), found offset {dx:g} {dy:g}")


def blocking_objects(room: Room) -> list[PlacedObject]:
    """Objects that stay where they start: static ones and dynamic ones with no trajectory."""
    return [o for o in room.objects
            if o.role == "static" or (o.role == "dynamic" and o.trajectory is None)]


def passable_floors(room: Room, layout: Layout) -> set[str]:
    """Floors the robot can drive to from its start: connected, no standing object on them."""
    robot = room.robot
    if robot is None or layout.origin is None or robot.floor.name not in room.floors:
        return set()
    blocked = {o.floor.name for o in blocking_objects(room)}
    free = [n for n in room.floors if n not in blocked and n in layout.cells]
    graph = layout.floor_graph.subgraph(free)
    if robot.floor.name not in graph:
        return set()
    return set(nx.node_connected_component(graph, robot.floor.name))


def check_types(room: Room, catalogue: Catalogue) -> list[Diagnostic]:
    out: list[Diagnostic] = []

    def check(name: str, type_name: str, span, expected_kind: str) -> ObjectType | None:  # type: ignore[no-untyped-def]
        otype = catalogue.get(type_name)
        if otype is None:
            out.append(Diagnostic(span, "CATALOGUE-TYPE",
                                  f"'{name}': expected a catalogue type, found '{type_name}'"
                                  + did_you_mean(type_name, catalogue.names())))
            return None
        if otype.kind != expected_kind:
            choices = ", ".join(catalogue.names(expected_kind)) or "none"  # type: ignore[arg-type]
            out.append(Diagnostic(span, "CATALOGUE-KIND",
                                  f"'{name}': expected a {expected_kind} type ({choices}), found "
                                  f"'{type_name}', which is a {otype.kind} type"))
            return None
        return otype

    for floor in room.floors.values():
        check(floor.name, floor.type, floor.span, "floor")
    for wall in room.walls.values():
        check(wall.name, wall.type, wall.span, "wall")
    half_tile = room.tile_size / 2
    for obj in room.objects:
        otype = check(obj.name, obj.type, obj.type_span, ROLE_KIND[obj.role])
        if otype is None or isinstance(otype.footprint, Tile):
            continue
        if obj.role == "robot":
            need = 2 * otype.footprint.circumradius()
            if need > room.tile_size + _FIT_SLACK:
                out.append(Diagnostic(obj.span, "ROBOT-FIT",
                                      f"robot '{obj.name}' ({obj.type}): expected tiles of at "
                                      f"least {need:.3f} m to turn in place, found tile size "
                                      f"{room.tile_size:g} m"))
            continue
        hx, hy = rotated_half_extents(otype, obj.heading_deg)
        if obj.offset != (0.0, 0.0) and max(hx, hy) <= half_tile + _FIT_SLACK:
            problem = offset_problem(obj.offset, room.tile_size, hx, hy)
            if problem:
                out.append(Diagnostic(obj.span, "OBJECT-FIT", f"'{obj.name}' ({obj.type}): "
                                                              f"expected {problem}"))
        elif max(hx, hy) > half_tile + _FIT_SLACK:
            out.append(Diagnostic(obj.span, "OBJECT-FIT",
                                  f"'{obj.name}' ({obj.type}, {2 * hx:.2f} x {2 * hy:.2f} m) "
                                  f"expected to fit its {room.tile_size:g} m tile, found it "
                                  f"overhangs into the neighbouring cells"))
    return out


def check_placement(room: Room, layout: Layout) -> list[Diagnostic]:
    out: list[Diagnostic] = []
    if room.robot is None:
        out.append(Diagnostic(room.span, "ROBOT-COUNT",
                              f"room '{room.name}': expected exactly one robot "
                              f"('robot NAME : TYPE on FLOOR'), found none"))
    first_on: dict[str, PlacedObject] = {}
    for obj in room.objects:
        floor = obj.floor.name
        if floor not in room.floors:
            continue
        if floor in first_on:
            other = first_on[floor]
            out.append(Diagnostic(obj.span, "OBJECT-OVERLAP",
                                  f"'{obj.name}': expected a floor of its own at the start, "
                                  f"found '{other.name}' already on '{floor}'"))
        else:
            first_on[floor] = obj
    reachable = passable_floors(room, layout)
    blocked = {o.floor.name: o for o in blocking_objects(room)}
    if room.robot is None or not reachable:
        return out
    for obj in room.objects:
        if obj.trajectory is None:
            continue
        for vertex in obj.trajectory.vertices:
            name = vertex.floor.name
            if name not in room.floors:
                continue
            problem = offset_problem(vertex.offset, room.tile_size, 0.0)
            if problem:
                out.append(Diagnostic(vertex.span, "OFFSET-TILE",
                                      f"trajectory of '{obj.name}': expected {problem}"))
            if name in blocked:
                out.append(Diagnostic(vertex.span, "TRAJ-BLOCKED",
                                      f"trajectory of '{obj.name}': expected a free floor, found "
                                      f"'{blocked[name].name}' standing on '{name}'"))
            elif name not in reachable:
                out.append(Diagnostic(vertex.span, "TRAJ-UNREACHABLE",
                                      f"trajectory of '{obj.name}': expected a vertex the robot "
                                      f"can reach, found '{name}' cut off from the robot's floor"))
    return out


_PATH_STEP = 0.02
"""Metres between the points of a walked curve that the clearance check looks at."""
_CLEAR_SLACK = 1e-6
"""Metres a disc may graze a wall or object before it counts as crossing it (rounding)."""


def check_trajectories(room: Room, layout: Layout, catalogue: Catalogue) -> list[Diagnostic]:
    """TRAJ-CROSSES: the curve a moving body walks keeps its footprint off walls, off
    standing objects and on the floors.

    The animator moves humans and dynamic objects along the Catmull-Rom spline through their
    timed vertices (rei.lang.room.spline), which overshoots the straight control polygon at
    sharp or unevenly timed turns; so the check samples that very spline and sweeps the
    body's disc (the radius the animator gives it: its catalogue footprint's largest half
    extent) along it. One located error per segment that touches something, at the
    segment's first vertex, naming the obstacle and how far the body goes into it.
    """
    out: list[Diagnostic] = []
    tile = room.tile_size
    at_cell = layout.block_at()
    obstacles = _standing_obstacles(room, layout, catalogue)
    for obj in room.objects:
        traj = obj.trajectory
        otype = catalogue.get(obj.type)
        if traj is None or len(traj.vertices) < 2 or otype is None:
            continue
        vertices = list(traj.vertices)
        if any(v.floor.name not in layout.cells or v.floor.name not in room.floors
               for v in vertices):
            continue  # unresolved vertices are reported by the linker
        times, points = vertex_times([vertex_point(v, layout.cells, tile) for v in vertices],
                                     [v.time for v in vertices], traj.total_time, traj.loop)
        if not walkable(times, points):
            continue  # TRAJ-SPEED says which segment the animator cannot walk
        try:
            spline = CatmullRom(np.array(times), np.array(points), traj.loop)
        except ValueError:
            continue  # vertex times out of order are reported by the linker
        radius = max(otype.footprint.half_extents())
        t, path = walked_path(spline, _PATH_STEP)
        rects, names = _obstacles_near(path, radius, tile, at_cell, obstacles)
        if not len(rects):
            continue
        depth = _penetration(path, radius, rects)  # (N, M)
        worst = depth.max(axis=1)
        segment = np.clip(np.searchsorted(spline.t, t, side="right") - 1, 0, len(times) - 2)
        for k in range(len(times) - 1):
            here = np.flatnonzero((segment == k) & (worst > _CLEAR_SLACK))
            if not len(here):
                continue
            at = int(here[np.argmax(worst[here])])
            hit = int(np.argmax(depth[at]))
            start = vertices[k]
            end = vertices[(k + 1) % len(vertices)]
            x, y = float(path[at, 0]), float(path[at, 1])
            out.append(Diagnostic(start.span, "TRAJ-CROSSES",
                                  f"trajectory of '{obj.name}': expected the curve it walks "
                                  f"from '{start.floor.name}' to '{end.floor.name}' (a "
                                  f"Catmull-Rom spline, its footprint {radius:.2f} m round) "
                                  f"to stay clear, found it {worst[at]:.2f} m into "
                                  f"{names[hit]} near ({x:.2f}, {y:.2f}) m"))
    return out


_Rect = tuple[float, float, float, float]
"""Centre x, centre y, half extent x, half extent y (metres, the concrete model's frame)."""


def _standing_obstacles(room: Room, layout: Layout, catalogue: Catalogue
                        ) -> dict[tuple[int, int], tuple[_Rect, str]]:
    """Walls (whole tiles) and objects that stay where they start (their rotated
    footprints), by cell."""
    tile = room.tile_size
    found: dict[tuple[int, int], tuple[_Rect, str]] = {}
    for name in room.walls:
        cell = layout.cells.get(name)
        if cell is not None:
            found[cell] = ((cell[0] * tile, cell[1] * tile, tile / 2, tile / 2),
                           f"the wall '{name}'")
    for obj in blocking_objects(room):
        cell = layout.cells.get(obj.floor.name)
        otype = catalogue.get(obj.type)
        if cell is None or otype is None or cell in found:
            continue
        hx, hy = (tile / 2, tile / 2) if isinstance(otype.footprint, Tile) else \
            rotated_half_extents(otype, obj.heading_deg)
        found[cell] = ((cell[0] * tile + obj.offset[0], cell[1] * tile + obj.offset[1], hx, hy),
                       f"'{obj.name}' standing on '{obj.floor.name}'")
    return found


def _obstacles_near(path: np.ndarray, radius: float, tile: float,
                    at_cell: dict[tuple[int, int], str],
                    obstacles: dict[tuple[int, int], tuple[_Rect, str]]
                    ) -> tuple[np.ndarray, list[str]]:
    """The obstacles of every cell the swept disc can reach: standing ones, and whole tiles
    where there is no floor."""
    reach = radius + tile
    lo = np.floor((path.min(axis=0) - reach) / tile).astype(int)
    hi = np.ceil((path.max(axis=0) + reach) / tile).astype(int)
    rects: list[_Rect] = []
    names: list[str] = []
    for i in range(int(lo[0]), int(hi[0]) + 1):
        for j in range(int(lo[1]), int(hi[1]) + 1):
            if (i, j) in obstacles:
                rect, name = obstacles[(i, j)]
            elif (i, j) not in at_cell:
                rect, name = (i * tile, j * tile, tile / 2, tile / 2), \
                    f"cell ({i}, {j}), where there is no floor"
            else:
                continue
            rects.append(rect)
            names.append(name)
    return np.array(rects, dtype=float).reshape(-1, 4), names


def _penetration(path: np.ndarray, radius: float, rects: np.ndarray) -> np.ndarray:
    """How far (m) a disc at each point reaches into each rectangle (<= 0: clear)."""
    dx = np.maximum(np.abs(path[:, None, 0] - rects[None, :, 0]) - rects[None, :, 2], 0.0)
    dy = np.maximum(np.abs(path[:, None, 1] - rects[None, :, 1]) - rects[None, :, 3], 0.0)
    return cast(np.ndarray, radius - np.hypot(dx, dy))
