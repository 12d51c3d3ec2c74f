"""The floor graph traversal of thesis 6.2.1 (Figure 26): every floor and wall gets a cell.

Starting from the robot's floor, a breadth-first traversal of the neighbour graph places
each floor one cell from its parent in the direction of the link; walls take the cell
beside the floor that names them. Cells are integer (i, j) with +i to the right and +j to
the top; metres are cells times the tile size (the generators' concern). Problems found
here: links that contradict the traversal, two blocks in one cell, walls claimed at two
places, walls no floor names, and floors the traversal cannot reach.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

import networkx as nx

from rei.lang.errors import Diagnostic
from rei.lang.room.model import Room

Cell = tuple[int, int]


@dataclass(frozen=True)
class Layout:
    origin: str | None
    """The floor the traversal started from (the robot's floor when it has one)."""
    cells: Mapping[str, Cell]
    """Cell of every placed floor and wall."""
    floor_graph: nx.Graph
    """Floors as nodes, neighbour links between floors as edges."""

    def block_at(self) -> dict[Cell, str]:
        return {cell: name for name, cell in self.cells.items()}


def floor_graph(room: Room) -> nx.Graph:
    graph: nx.Graph = nx.Graph()
    graph.add_nodes_from(room.floors)
    for name, links in room.neighbours.items():
        for target in links.values():
            if target in room.floors:
                graph.add_edge(name, target)
    return graph


def compute_layout(room: Room) -> tuple[Layout, list[Diagnostic]]:
    diagnostics: list[Diagnostic] = []
    graph = floor_graph(room)
    robot = room.robot
    origin: str | None = None
    if robot is not None and robot.floor.name in room.floors:
        origin = robot.floor.name
    elif room.floors:
        origin = next(iter(room.floors))
    cells: dict[str, Cell] = {}
    if origin is None:
        return Layout(None, MappingProxyType(cells), graph), diagnostics

    cells[origin] = (0, 0)
    for parent, child in nx.bfs_edges(graph, origin):
        di, dj = _direction(room, parent, child)
        pi, pj = cells[parent]
        cells[child] = (pi + di, pj + dj)

    occupant: dict[Cell, str] = {}
    for name in room.floors:  # declaration order, so the later one is reported
        if name not in cells:
            continue
        cell = cells[name]
        if cell in occupant:
            diagnostics.append(Diagnostic(
                room.floors[name].span, "FLOOR-OVERLAP",
                f"expected each floor in a cell of its own, found '{name}' placed in cell {cell} "
                f"of '{occupant[cell]}' by the neighbour links"))
        else:
            occupant[cell] = name

    for name, links in room.neighbours.items():
        if name not in cells:
            continue
        ci, cj = cells[name]
        for side, target in links.items():
            di, dj = side.delta
            expected = (ci + di, cj + dj)
            if target in room.floors:
                if target in cells and cells[target] != expected and _written(room, name, side):
                    ref_span = _link_span(room, name, side)
                    diagnostics.append(Diagnostic(
                        ref_span, "LINK-GEOMETRY",
                        f"floor '{name}' has '{target}' on its {side.keyword} side, expected at "
                        f"cell {expected}, found the traversal from '{origin}' places it at "
                        f"{cells[target]}"))
            elif target in room.walls:
                if target in cells and cells[target] != expected:
                    diagnostics.append(Diagnostic(
                        _link_span(room, name, side), "WALL-PLACEMENT",
                        f"wall '{target}' is the {side.keyword} neighbour of '{name}' (cell "
                        f"{expected}), expected one cell for it, found it also at "
                        f"{cells[target]}"))
                    continue
                cells.setdefault(target, expected)
                if expected in occupant and occupant[expected] != target:
                    other = occupant[expected]
                    if other in room.floors:
                        diagnostics.append(Diagnostic(
                            room.walls[target].span, "FLOOR-OVERLAP",
                            f"expected wall '{target}' in a free cell, found it in cell "
                            f"{expected} of floor '{other}'"))
                else:
                    occupant.setdefault(expected, target)

    _place_grid_walls(room, cells, occupant)
    for wall in room.walls.values():
        if wall.name not in cells:
            diagnostics.append(Diagnostic(
                wall.span, "WALL-ORPHAN",
                f"expected wall '{wall.name}' to be the neighbour of a floor, found no floor "
                f"that names it"))

    # Components in declaration order of their first floor; index maps keep this linear
    # (a room of 200,000 disconnected floors is 200,000 components).
    order = {name: i for i, name in enumerate(room.floors)}
    unreached = [n for n in room.floors if n not in cells]
    sizes = {min(c, key=order.__getitem__): len(c)
             for c in nx.connected_components(graph.subgraph(unreached))}
    for first in sorted(sizes, key=order.__getitem__):
        component_size = sizes[first]
        diagnostics.append(Diagnostic(
            room.floors[first].span, "FLOOR-DISCONNECTED",
            f"expected every floor connected to '{origin}', found {component_size} floor(s) "
            f"starting with '{first}' that no neighbour link reaches"))
    return Layout(origin, MappingProxyType(cells), graph), diagnostics


def _written(room: Room, name: str, side: object) -> bool:
    return any(s is side for s, _ in room.floors[name].links)


def _link_span(room: Room, name: str, side: object):  # type: ignore[no-untyped-def]
    for s, ref in room.floors[name].links:
        if s is side:
            return ref.span
    return room.floors[name].span


def _place_grid_walls(room: Room, cells: dict[str, Cell], occupant: dict[Cell, str]) -> None:
    """Walls of a grid that touch no floor (corners) take their cell from the grid itself."""
    for grid in room.grids:
        anchor = next(((rc, n) for rc, n in grid.cells.items() if n in room.floors and n in cells),
                      None)
        if anchor is None:
            continue
        (ar, ac), aname = anchor
        ai, aj = cells[aname]
        for (r, c), name in grid.cells.items():
            if name in room.walls and name not in cells:
                cell = (ai + c - ac, aj - (r - ar))
                if cell not in occupant:
                    cells[name] = cell
                    occupant[cell] = name


def _direction(room: Room, parent: str, child: str) -> Cell:
    """The cell offset from parent to child: the parent's link, else the child's reversed."""
    for side, target in room.neighbours[parent].items():
        if target == child:
            return side.delta
    for side, target in room.neighbours[child].items():
        if target == parent:
            return side.opposite.delta
    raise AssertionError(f"no link between {parent} and {child}")  # edges come from links
