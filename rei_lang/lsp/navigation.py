"""What name is under the cursor in a room or mission, where it is declared, what it means.

Everything here reads the checked models (``RoomDocument``, ``MissionDocument``) and their
spans; it never parses or checks anything itself, so hover and go-to-definition can only
say what ``rei-gen check`` and the generators also believe.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass
from importlib import resources
from typing import Literal

from rei.catalogue import Box, Catalogue, Cylinder, ObjectType, Polygon, Tile
from rei.lang.errors import Diagnostic, Span
from rei.lang.lsp.positions import LineIndex, contains
from rei.lang.mission.document import MissionDocument
from rei.lang.room.document import RoomDocument
from rei.lang.room.model import PlacedObject, Room, Side
from rei.lang.source import read_source

Kind = Literal["block", "object", "type", "file"]
DEFAULT_CATALOGUE_SOURCE = "<default catalogue>"


@dataclass(frozen=True)
class Place:
    """A region of a file, with the text it was measured in (for code-unit conversion)."""

    path: str
    span: Span
    text: str | None


@dataclass(frozen=True)
class Written:
    """A name as written in a file: where, and what kind of thing it names."""

    span: Span
    kind: Kind
    name: str


@dataclass(frozen=True)
class Found:
    """The name under the cursor: where it is written, where declared, and a hover text."""

    written: Written
    declaration: Place | None
    hover: str


def name_span(index: LineIndex, span: Span, name: str, prefix: str = "") -> Span:
    """The span of ``name`` as a whole word in the first line of ``span`` (optionally right
    after the regex ``prefix``); the span itself when it cannot be found."""
    line = index.line_text(span.line)
    end = span.end_col - 1 if span.end_line == span.line else len(line)
    segment = line[span.col - 1:end]
    match = re.search(rf"{prefix}(?<![\w])({re.escape(name)})(?![\w])", segment)
    if match is None:
        return span
    start = span.col + match.start(1)
    return Span(span.file, span.line, start, span.line, start + len(name))


def grid_cell_span(row_span: Span, col: int) -> Span:
    """The span of one character of a grid row (the row span starts at its opening quote)."""
    return Span(row_span.file, row_span.line, row_span.col + 1 + col, row_span.line,
                row_span.col + 2 + col)


# --- names written in a room ---------------------------------------------------------------

def room_names(room: Room, index: LineIndex) -> Iterator[Written]:
    """Every name written in a room file: declarations and references, in no fixed order."""
    for grid in room.grids:
        for (r, c), name in grid.cells.items():
            if r < len(grid.row_spans):
                yield Written(grid_cell_span(grid.row_spans[r], c), "block", name)
    for floor in room.floors.values():
        if floor.cell_of_grid is not None:
            continue
        yield Written(name_span(index, floor.span, floor.name), "block", floor.name)
        for _, ref in floor.links:
            yield Written(ref.span, "block", ref.name)
    for wall in room.walls.values():
        if wall.cell_of_grid is None:
            yield Written(name_span(index, wall.span, wall.name), "block", wall.name)
    for obj in room.objects:
        yield Written(name_span(index, obj.span, obj.name), "object", obj.name)
        if obj.type:
            type_span = name_span(index, obj.type_span, obj.type, prefix=r":\s*")
            if type_span != obj.type_span:
                yield Written(type_span, "type", obj.type)
        yield Written(obj.floor.span, "block", obj.floor.name)
        if obj.trajectory is not None:
            for vertex in obj.trajectory.vertices:
                yield Written(vertex.floor.span, "block", vertex.floor.name)
            trigger = obj.trajectory.trigger
            if trigger is not None:
                yield Written(trigger.floor.span, "block", trigger.floor.name)


def _smallest_at(names: Iterator[Written], line: int, col: int) -> Written | None:
    best: Written | None = None
    for written in names:
        s = written.span
        if not contains(s, line, col):
            continue
        if best is None or (s.end_line - s.line, s.end_col - s.col) < (
                best.span.end_line - best.span.line, best.span.end_col - best.span.col):
            best = written
    return best


def find_in_room(doc: RoomDocument, index: LineIndex, line: int, col: int) -> Found | None:
    room = doc.room
    if room is None:
        return None
    # A grid cell is one character: the cursor is on the character to its right.
    for grid in room.grids:
        for r, row_span in enumerate(grid.row_spans):
            if row_span.line == line:
                name = grid.cells.get((r, col - row_span.col - 1))
                if name is not None:
                    return describe(doc, Written(grid_cell_span(row_span, col - row_span.col - 1),
                                                 "block", name), index)
    if room.catalogue_span is not None and room.catalogue_path is not None and contains(
            room.catalogue_span, line, col):
        catalogue = Written(room.catalogue_span, "file", room.catalogue_path)
        return Found(catalogue, _file_place(room.catalogue_path),
                     f"catalogue file `{room.catalogue_path}`")
    written = _smallest_at(room_names(room, index), line, col)
    return describe(doc, written, index) if written is not None else None


def find_in_mission(doc: MissionDocument, index: LineIndex, line: int, col: int
                    ) -> Found | None:
    mission = doc.mission
    if mission is None:
        return None
    if contains(mission.room_span, line, col):
        written = Written(mission.room_span, "file", mission.room_path)
        room_name = doc.room.room.name if doc.room is not None and doc.room.room else None
        hover = f"room file `{mission.room_path}`" + (f" (room `{room_name}`)" if room_name
                                                       else "")
        return Found(written, _file_place(mission.room_path), hover)
    for goal in mission.goals:
        if contains(goal.floor.span, line, col):
            written = Written(goal.floor.span, "block", goal.floor.name)
            if doc.room is None or doc.room.room is None:
                return Found(written, None, f"floor `{goal.floor.name}` (its room does not parse)")
            room_index = LineIndex.of(doc.room.source.text if doc.room.source else "")
            found = describe(doc.room, written, room_index)
            return found
    return None


def _file_place(path: str) -> Place:
    return Place(path, Span.point(path), None)


# --- what a name means ---------------------------------------------------------------------

def describe(doc: RoomDocument, written: Written, index: LineIndex) -> Found:
    """Where the name is declared and a hover text for it."""
    room = doc.room
    assert room is not None
    text = doc.source.text if doc.source is not None else None
    if written.kind == "type":
        return _describe_type(doc, written)
    if written.kind == "object":
        obj = next((o for o in room.objects if o.name == written.name), None)
        if obj is None:
            return Found(written, None, f"`{written.name}`: no such object")
        place = Place(room.path, name_span(index, obj.span, obj.name), text)
        return Found(written, place, _object_hover(doc, obj))
    name = written.name
    if name in room.floors:
        decl = room.floors[name]
        span = decl.span if decl.cell_of_grid else name_span(index, decl.span, name)
        return Found(written, Place(room.path, span, text), _floor_hover(doc, name))
    if name in room.walls:
        wall = room.walls[name]
        span = wall.span if wall.cell_of_grid else name_span(index, wall.span, name)
        return Found(written, Place(room.path, span, text), _wall_hover(doc, name))
    obj = next((o for o in room.objects if o.name == name), None)
    if obj is not None:
        place = Place(room.path, name_span(index, obj.span, obj.name), text)
        return Found(written, place, _object_hover(doc, obj))
    return Found(written, None, f"`{name}`: not a floor, wall or object of room `{room.name}`")


def _metres(doc: RoomDocument, name: str) -> str:
    room = doc.room
    assert room is not None
    if doc.layout is None or name not in doc.layout.cells:
        return "not placed (no neighbour link reaches it)"
    i, j = doc.layout.cells[name]
    t = room.tile_size
    origin = doc.layout.origin
    return (f"cell ({i}, {j}), centre at ({i * t:g}, {j * t:g}) m from the centre of "
            f"`{origin}`")


def _grid_place(decl_cell: object) -> str:
    cell = decl_cell
    if cell is None:
        return ""
    return f"\n\ngrid `{cell.grid}`, row {cell.row}, column {cell.col}"  # type: ignore[attr-defined]


def _floor_hover(doc: RoomDocument, name: str) -> str:
    room = doc.room
    assert room is not None
    decl = room.floors[name]
    links = room.neighbours.get(name, {})
    sides = " · ".join(f"{side.keyword} `{links[side]}`" if side in links else f"{side.keyword} —"
                       for side in (Side.TOP, Side.RIGHT, Side.BOTTOM, Side.LEFT))
    lines = [f"**floor** `{name}` : {decl.type}", "", _metres(doc, name),
             "", f"neighbours: {sides}"]
    on_it = room.objects_on(name)
    if on_it:
        lines += ["", "on it: " + ", ".join(f"`{o.name}` ({o.type})" for o in on_it)]
    return "\n".join(lines) + _grid_place(decl.cell_of_grid)


def _wall_hover(doc: RoomDocument, name: str) -> str:
    room = doc.room
    assert room is not None
    wall = room.walls[name]
    return f"**wall** `{name}` : {wall.type}\n\n{_metres(doc, name)}" + _grid_place(
        wall.cell_of_grid)


def _catalogue(doc: RoomDocument) -> Catalogue | None:
    if doc.catalogue is not None:
        return doc.catalogue
    from rei.catalogue import default_catalogue  # the room's own catalogue did not load

    return default_catalogue()


def footprint_text(object_type: ObjectType, tile: float) -> str:
    shape = object_type.footprint
    if isinstance(shape, Box):
        return f"box {shape.size_x:g} × {shape.size_y:g} m"
    if isinstance(shape, Cylinder):
        return f"cylinder of radius {shape.radius:g} m"
    if isinstance(shape, Polygon):
        hx, hy = shape.half_extents()
        return f"polygon of {len(shape.points)} points within {2 * hx:g} × {2 * hy:g} m"
    if isinstance(shape, Tile):
        return f"one tile ({tile:g} × {tile:g} m)"
    return str(shape)


def type_text(object_type: ObjectType, tile: float) -> str:
    lines = [f"**{object_type.kind}** type `{object_type.name}`"]
    if object_type.description:
        lines += ["", object_type.description]
    lines += ["", f"footprint: {footprint_text(object_type, tile)}; height "
                  f"{object_type.height:g} m; mass {object_type.mass:g} kg"]
    return "\n".join(lines)


def _object_hover(doc: RoomDocument, obj: PlacedObject) -> str:
    room = doc.room
    assert room is not None
    lines = [f"**{obj.role}** `{obj.name}` : {obj.type} on `{obj.floor.name}`"]
    if obj.heading_deg is not None:
        lines[0] += f", heading {obj.heading_deg:g}°"
    if obj.floor.name in room.floors:
        lines += ["", "at " + _metres(doc, obj.floor.name)]
    catalogue = _catalogue(doc)
    object_type = catalogue.get(obj.type) if catalogue is not None else None
    if object_type is None:
        lines += ["", f"type `{obj.type}` is not in the catalogue"]
    else:
        lines += ["", type_text(object_type, room.tile_size)]
    if obj.trajectory is not None:
        route = " → ".join(v.floor.name for v in obj.trajectory.vertices)
        lines += ["", f"trajectory ({'loop' if obj.trajectory.loop else 'stop'}): {route}"]
        trigger = obj.trajectory.trigger
        if trigger is not None:
            lines.append(f"starts when the robot is within {trigger.distance:g} m of "
                         f"`{trigger.floor.name}`")
    return "\n".join(lines)


def _describe_type(doc: RoomDocument, written: Written) -> Found:
    room = doc.room
    assert room is not None
    catalogue = _catalogue(doc)
    object_type = catalogue.get(written.name) if catalogue is not None else None
    if object_type is None or catalogue is None:
        return Found(written, None, f"type `{written.name}` is not in the catalogue")
    return Found(written, type_declaration(catalogue, written.name),
                 type_text(object_type, room.tile_size))


def catalogue_file(source: str) -> str:
    if source == DEFAULT_CATALOGUE_SOURCE:
        return str(resources.files("rei.catalogue").joinpath("default.toml"))
    return source


def type_declaration(catalogue: Catalogue, name: str) -> Place | None:
    """The ``[types.NAME]`` table of the catalogue file that defines the type (the last one
    wins, as when catalogues are merged)."""
    pattern = re.compile(rf"^[ \t]*\[types\.{re.escape(name)}[\].]", re.MULTILINE)
    for source in reversed(catalogue.sources):
        path = catalogue_file(source)
        source_text = read_source(path)  # bounded, and never blocks on a FIFO
        if isinstance(source_text, Diagnostic):
            continue
        text = source_text.text
        match = pattern.search(text)
        if match is None:
            continue
        line = text.count("\n", 0, match.start()) + 1
        line_text = text.split("\n")[line - 1]
        return Place(path, Span(path, line, 1, line, len(line_text) + 1), text)
    return None
