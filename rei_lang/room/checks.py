"""Room rules that need the catalogue or the layout: types, sizes, overlaps, reachability."""

from __future__ import annotations

import math
from itertools import pairwise

import networkx as nx

from rei.catalogue import Catalogue, ObjectType, Tile
from rei.lang.errors import Diagnostic
from rei.lang.room.layout import Layout
from rei.lang.room.model import PlacedObject, Room
from rei.lang.suggest import did_you_mean

ROLE_KIND = {"static": "static", "dynamic": "dynamic", "human": "human", "robot": "robot"}
_FIT_SLACK = 1e-9


def rotated_half_extents(otype: ObjectType, heading_deg: float | None) -> tuple[float, float]:
    hx, hy = otype.footprint.half_extents()
    a = math.radians(heading_deg or 0.0)
    c, s = abs(math.cos(a)), abs(math.sin(a))
    return c * hx + s * hy, s * hx + c * hy


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
        if max(hx, hy) > half_tile + _FIT_SLACK:
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
    out.extend(_check_trajectory_ways(room, layout))
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
            if name in blocked:
                out.append(Diagnostic(vertex.span, "TRAJ-BLOCKED",
                                      f"trajectory of '{obj.name}': expected a free floor, found "
                                      f"'{blocked[name].name}' standing on '{name}'"))
            elif name not in reachable:
                out.append(Diagnostic(vertex.span, "TRAJ-UNREACHABLE",
                                      f"trajectory of '{obj.name}': expected a vertex the robot "
                                      f"can reach, found '{name}' cut off from the robot's floor"))
    return out


_WAY_STEP = 0.1
"""Sampling step along a trajectory's way between vertices, in tiles."""


def _check_trajectory_ways(room: Room, layout: Layout) -> list[Diagnostic]:
    """The straight way between consecutive vertices stays on floors free of standing objects.

    The animator's spline bends a little around the vertices; the straight way is the check
    a person would make on a floor plan, and it catches walking through walls and furniture.
    """
    out: list[Diagnostic] = []
    at_cell = layout.block_at()
    blocked = {o.floor.name: o.name for o in blocking_objects(room)}
    for obj in room.objects:
        traj = obj.trajectory
        if traj is None or len(traj.vertices) < 2:
            continue
        vertices = list(traj.vertices)
        if any(v.floor.name not in layout.cells or v.floor.name not in room.floors
               for v in vertices):
            continue  # unresolved vertices are reported by the linker
        pairs = list(pairwise(vertices))
        if traj.loop:
            pairs.append((vertices[-1], vertices[0]))
        for start, end in pairs:
            problem = _first_obstacle(layout.cells[start.floor.name], layout.cells[end.floor.name],
                                      at_cell, room, blocked)
            if problem is not None:
                out.append(Diagnostic(start.span, "TRAJ-CROSSES",
                                      f"trajectory of '{obj.name}': expected the way from "
                                      f"'{start.floor.name}' to '{end.floor.name}' to stay on "
                                      f"free floors, found it crosses {problem}"))
    return out


def _first_obstacle(a: tuple[int, int], b: tuple[int, int], at_cell: dict[tuple[int, int], str],
                    room: Room, blocked: dict[str, str]) -> str | None:
    steps = max(1, int(math.hypot(b[0] - a[0], b[1] - a[1]) / _WAY_STEP))
    for k in range(steps + 1):
        t = k / steps
        cell = (math.floor(a[0] + (b[0] - a[0]) * t + 0.5),
                math.floor(a[1] + (b[1] - a[1]) * t + 0.5))
        name = at_cell.get(cell)
        if name is None:
            return f"cell {cell}, where there is no floor"
        if name in room.walls:
            return f"the wall '{name}'"
        if name in blocked:
            return f"'{blocked[name]}' standing on '{name}'"
    return None
