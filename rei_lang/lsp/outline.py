"""Document symbols (the editor's outline) of rooms and missions, from their checked models.

A room's grid appears with its cells as children, each named by the floor or wall it
declares, so a reader sees which name a character of the grid stands for. This module
builds plain records; the server turns them into LSP symbols. It must never check a rule.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from rei.lang.errors import Span
from rei.lang.lsp.navigation import grid_cell_span, name_span
from rei.lang.lsp.positions import LineIndex
from rei.lang.mission.model import Mission
from rei.lang.room.model import Room


@dataclass(frozen=True)
class Symbol:
    name: str
    kind: str
    """room | grid | floor | wall | object | robot | human | mission | goal | fault |
    declaration"""
    detail: str
    span: Span
    selection: Span
    children: tuple[Symbol, ...] = field(default=())


def room_outline(room: Room, index: LineIndex) -> Symbol:
    children: list[Symbol] = []
    for grid in room.grids:
        cells: list[Symbol] = []
        for (r, c), name in sorted(grid.cells.items()):
            if r >= len(grid.row_spans):
                continue
            span = grid_cell_span(grid.row_spans[r], c)
            kind = "floor" if name in room.floors else "wall"
            cells.append(Symbol(name, kind, f"{kind}, row {r} column {c}", span, span))
        width = max((len(row) for row in grid.rows), default=0)
        children.append(Symbol(grid.name, "grid", f"grid {len(grid.rows)} × {width}", grid.span,
                               name_span(index, grid.span, grid.name), tuple(cells)))
    for floor in room.floors.values():
        if floor.cell_of_grid is None:
            children.append(Symbol(floor.name, "floor", f"floor : {floor.type}", floor.span,
                                   name_span(index, floor.span, floor.name)))
    for wall in room.walls.values():
        if wall.cell_of_grid is None:
            children.append(Symbol(wall.name, "wall", f"wall : {wall.type}", wall.span,
                                   name_span(index, wall.span, wall.name)))
    for obj in room.objects:
        kind = obj.role if obj.role in ("robot", "human") else "object"
        children.append(Symbol(obj.name, kind, f"{obj.role} : {obj.type} on {obj.floor.name}",
                               obj.span, name_span(index, obj.span, obj.name)))
    children.sort(key=lambda s: (s.span.line, s.span.col))
    return Symbol(room.name, "room", "room", room.span, name_span(index, room.span, room.name),
                  tuple(children))


def mission_outline(mission: Mission, index: LineIndex) -> Symbol:
    goals = [Symbol(goal.name, "goal", f"goal at {goal.floor.name}", goal.span,
                    goal.floor.span)
             for goal in mission.goals]
    faults = [Symbol(fault.name, "fault", fault.text(), fault.span, fault.span)
              for fault in mission.faults if fault.span is not None]
    children = sorted(goals + faults, key=lambda s: (s.span.line, s.span.col))
    return Symbol(mission.name, "mission", f"mission in {mission.room_path}", mission.span,
                  name_span(index, mission.span, mission.name), tuple(children))
