"""From a parsed .room (textX model) to the typed Room, resolving every name.

Reports every problem of the file at once: duplicate names, unresolved or wrongly-kinded
references (with 'did you mean'), disagreeing neighbour links, grid legend problems, and
numbers that are not finite or out of range. Geometry (cells, overlaps, connectivity,
reachability) is checked afterwards by rei.lang.room.layout.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import pairwise
from pathlib import Path
from types import MappingProxyType
from typing import Any

from rei.lang.errors import Diagnostic, Span
from rei.lang.numbers import NO_OFFSET, read_number, read_offset
from rei.lang.parsing import span_at, span_of
from rei.lang.room.model import (
    BEHAVIOURS,
    DEFAULT_BEHAVIOUR,
    DEFAULT_TILE_SIZE,
    Behaviour,
    FloorDecl,
    GridCell,
    GridDecl,
    NameRef,
    PlacedObject,
    Role,
    Room,
    Side,
    StartTrigger,
    Trajectory,
    Vertex,
    WallDecl,
)
from rei.lang.source import SourceText
from rei.lang.suggest import did_you_mean

DEFAULT_LEGEND = {".": "floor", "#": "wall", " ": "empty", "_": "empty"}
RESERVED_NAMES = {"con", "prn", "aux", "nul", *(f"com{i}" for i in range(10)),
                  *(f"lpt{i}" for i in range(10))}
MAX_NAME_LENGTH = 100
MAX_TIME = 1.0e6
MAX_TILE = 100.0
MAX_TRIGGER_DISTANCE = 1.0e3
"""m: a start trigger farther than this from its floor is a typo, not a room."""
MIN_TILE = 0.05
DEFAULT_TYPES: dict[Role, str] = {"human": "human"}


@dataclass
class _Linker:
    source: SourceText
    diagnostics: list[Diagnostic] = field(default_factory=list)
    declared: dict[str, Span] = field(default_factory=dict)

    def span(self, obj: Any) -> Span:
        return span_of(obj, self.source)

    def error(self, span: Span, rule: str, message: str) -> None:
        self.diagnostics.append(Diagnostic(span, rule, message))

    def ref(self, ref: Any) -> NameRef:
        return NameRef(ref.name, self.span(ref))

    def number(self, text: str | None, obj: Any, what: str, **bounds: Any) -> float | None:
        if text is None:
            return None
        return read_number(text, self.span(obj), what, self.diagnostics, **bounds)

    def offset(self, raw: Any, what: str) -> tuple[float, float]:
        if raw is None:
            return NO_OFFSET
        return read_offset(raw.dx, raw.dy, self.span(raw), what, self.diagnostics)

    def declare(self, name: str, span: Span) -> None:
        if name in self.declared:
            first = self.declared[name]
            self.error(span, "NAME-UNIQUE",
                       f"expected a unique name, found '{name}' again (first declared at line "
                       f"{first.line})")
            return
        self.declared[name] = span
        if name.lower() in RESERVED_NAMES:
            self.error(span, "NAME-PATH",
                       f"expected a name that is safe as a file name, found the reserved "
                       f"device name '{name}'")
        elif len(name) > MAX_NAME_LENGTH:
            self.error(span, "NAME-PATH",
                       f"expected a name of at most {MAX_NAME_LENGTH} characters, found "
                       f"{len(name)}")


def _legend(linker: _Linker, grid: Any) -> dict[str, tuple[str, str | None, str | None, Span]]:
    legend: dict[str, tuple[str, str | None, str | None, Span]] = {
        sym: (kind, None, None, linker.span(grid)) for sym, kind in DEFAULT_LEGEND.items()
    }
    if grid.legend is None:
        return legend
    for entry in grid.legend.entries:
        span = linker.span(entry)
        if len(entry.symbol) != 1:
            linker.error(span, "GRID-LEGEND",
                         f"expected a single character as a legend symbol, found '{entry.symbol}'")
            continue
        if entry.cell is not None and entry.kind == "empty":
            linker.error(span, "GRID-LEGEND", "expected no name for an empty cell, found "
                         f"'{entry.cell}'")
        legend[entry.symbol] = (entry.kind, entry.cell, entry.type, span)
    return legend


_GRID_NEIGHBOURS = ((Side.TOP, -1, 0), (Side.RIGHT, 0, 1), (Side.BOTTOM, 1, 0),
                    (Side.LEFT, 0, -1))
"""A grid's first row is its top: the top neighbour is one row up."""


def _expand_grid(linker: _Linker, grid: Any, floors: dict[str, FloorDecl],
                 walls: dict[str, WallDecl]) -> GridDecl:
    legend = _legend(linker, grid)
    gspan = linker.span(grid)
    rows = tuple(grid.rows)
    # textX does not keep positions of STRING matches: find each row in the grid's text.
    row_spans: list[Span] = []
    text = linker.source.text
    pos = grid._tx_position
    for row in rows:
        found = text.find(f'"{row}"', pos)
        if found < 0:
            found = text.find(f"'{row}'", pos)
        start = found if found >= 0 else grid._tx_position
        pos = start + len(row) + 2
        row_spans.append(span_at(linker.source, start, pos))
    kinds: dict[tuple[int, int], tuple[str, str, str | None, Span]] = {}
    named_used: dict[str, Span] = {}
    for r, row in enumerate(rows):
        line, col0 = row_spans[r].line, row_spans[r].col + 1
        for c, sym in enumerate(row):
            if sym in " _" and legend.get(sym, ("",))[0] == "empty":
                continue  # the common case of an empty cell, without building its span
            cell_span = Span(gspan.file, line, col0 + c, line, col0 + c + 1)
            if sym not in legend:
                known = "".join(sorted(legend))
                linker.error(cell_span, "GRID-SYMBOL",
                             f"expected a legend symbol (one of '{known}'), found '{sym}' "
                             f"in row {r} column {c} of grid '{grid.name}'")
                continue
            kind, cell_name, type_name, _ = legend[sym]
            if kind == "empty":
                continue
            name = cell_name or f"{grid.name}_{r}_{c}"
            if cell_name is not None:
                if cell_name in named_used:
                    linker.error(cell_span, "GRID-SYMBOL",
                                 f"expected the named cell '{cell_name}' (symbol '{sym}') once, "
                                 f"found it again (first at line {named_used[cell_name].line})")
                    continue
                named_used[cell_name] = cell_span
            kinds[(r, c)] = (kind, name, type_name, cell_span)
            linker.declare(name, cell_span)
    names = {rc: v[1] for rc, v in kinds.items()}
    for (r, c), (kind, name, type_name, cell_span) in kinds.items():
        cell = GridCell(grid.name, r, c)
        if kind == "wall":
            walls.setdefault(name, WallDecl(name, type_name or "wall", cell_span, cell))
            continue
        links: list[tuple[Side, NameRef]] = []
        for side, dr, dc in _GRID_NEIGHBOURS:
            other = names.get((r + dr, c + dc))
            if other is not None:
                links.append((side, NameRef(other, cell_span)))
        floors.setdefault(name, FloorDecl(name, type_name or "floor_tile", cell_span,
                                          tuple(links), cell))
    return GridDecl(grid.name, gspan, rows, tuple(row_spans), MappingProxyType(names))


def _trajectory(linker: _Linker, raw: Any, owner: str) -> Trajectory | None:
    if raw is None:
        return None
    span = linker.span(raw)
    total: float | None = None
    loop: bool | None = None
    trigger: StartTrigger | None = None
    for option in raw.options:
        kind = type(option).__name__
        if kind == "StartTrigger":
            if trigger is not None:
                linker.error(linker.span(option), "OPTION-REPEAT",
                             f"trajectory of '{owner}': expected one 'when robot within', found "
                             f"another")
            distance = linker.number(option.distance, option,
                                     f"start distance of '{owner}'s trajectory (m)", low=0.0,
                                     high=MAX_TRIGGER_DISTANCE, low_open=True)
            trigger = StartTrigger(linker.ref(option.floor), distance or 0.0,
                                   linker.span(option))
        elif kind == "TotalTime":
            if total is not None:
                linker.error(linker.span(option), "OPTION-REPEAT",
                             f"trajectory of '{owner}': expected one 'total', found another")
            total = linker.number(option.seconds, option, f"total time of '{owner}'s trajectory",
                                  low=0.0, high=MAX_TIME, low_open=True)
        else:
            if loop is not None:
                linker.error(linker.span(option), "OPTION-REPEAT",
                             f"trajectory of '{owner}': expected one of 'loop' or 'stop', "
                             f"found another")
            loop = option.mode == "loop"
    vertices = tuple(
        Vertex(linker.ref(v.floor),
               linker.number(v.time, v, f"time of a vertex of '{owner}'s trajectory",
                             low=0.0, high=MAX_TIME),
               linker.span(v),
               linker.offset(v.offset, f"offset of a vertex of '{owner}'s trajectory"))
        for v in raw.vertices
    )
    if len(vertices) < 2:
        linker.error(span, "TRAJ-VERTICES",
                     f"trajectory of '{owner}': expected at least 2 control vertices, found "
                     f"{len(vertices)}")
    timed = [v for v in raw.vertices if v.time is not None]
    if timed and len(timed) != len(vertices):
        linker.error(span, "TRAJ-TIMES",
                     f"trajectory of '{owner}': expected a time on every vertex or on none, "
                     f"found {len(timed)} of {len(vertices)}")
    elif timed and total is not None:
        linker.error(span, "TRAJ-TIMES",
                     f"trajectory of '{owner}': expected either vertex times or a 'total', "
                     f"found both")
    elif not timed and total is None and len(vertices) >= 2:
        linker.error(span, "TRAJ-TIMES",
                     f"trajectory of '{owner}': expected vertex times ('FLOOR at SECONDS') or "
                     f"'total SECONDS', found neither")
    elif timed:
        for prev, cur in pairwise(vertices):
            if prev.time is not None and cur.time is not None and cur.time <= prev.time:
                linker.error(cur.span, "TRAJ-TIMES",
                             f"trajectory of '{owner}': expected times to increase, found "
                             f"{cur.time:g} after {prev.time:g}")
    return Trajectory(vertices, total, bool(loop), span, trigger)


def _behaviour(linker: _Linker, raw: Any, owner: str) -> Behaviour:
    """The human's behaviour; an unknown name is reported (with 'did you mean') and read as
    the default, so the rest of the file is still checked."""
    if raw is None:
        return DEFAULT_BEHAVIOUR
    for known in BEHAVIOURS:
        if raw.name == known:
            return known
    linker.error(linker.span(raw), "HUMAN-BEHAVIOUR",
                 f"human '{owner}': expected a behaviour ({', '.join(BEHAVIOURS)}), found "
                 f"'{raw.name}'" + did_you_mean(raw.name, BEHAVIOURS))
    return DEFAULT_BEHAVIOUR


def link_room(textx_room: Any, source: SourceText) -> tuple[Room, list[Diagnostic]]:
    """The typed room and every linking problem of the file."""
    linker = _Linker(source)
    floors: dict[str, FloorDecl] = {}
    walls: dict[str, WallDecl] = {}
    objects: list[PlacedObject] = []
    grids: list[GridDecl] = []
    tile: float | None = None
    tile_seen = False
    catalogue_path: str | None = None
    catalogue_span: Span | None = None

    for item in textx_room.items:
        kind = type(item).__name__
        span = linker.span(item)
        if kind == "TileSetting":
            if tile_seen:
                linker.error(span, "OPTION-REPEAT", "expected one 'tile' setting, found another")
            tile_seen = True
            tile = linker.number(item.size, item, "tile size (metres)", low=MIN_TILE,
                                 high=MAX_TILE)
        elif kind == "CatalogueSetting":
            if catalogue_span is not None:
                linker.error(span, "OPTION-REPEAT",
                             "expected one 'catalogue' setting, found another")
                continue
            catalogue_span = span
            candidate = Path(source.path).parent / item.path
            catalogue_path = str(candidate)
        elif kind == "Grid":
            grids.append(_expand_grid(linker, item, floors, walls))
        elif kind == "Floor":
            linker.declare(item.name, span)
            seen_sides: set[Side] = set()
            links: list[tuple[Side, NameRef]] = []
            for link in item.links:
                side = Side[link.side.upper()]
                if side in seen_sides:
                    linker.error(linker.span(link), "LINK-REPEAT",
                                 f"floor '{item.name}': expected one '{link.side}' neighbour, "
                                 f"found another")
                    continue
                seen_sides.add(side)
                links.append((side, linker.ref(link.target)))
            floors.setdefault(item.name, FloorDecl(item.name, item.type or "floor_tile", span,
                                                   tuple(links)))
        elif kind == "Wall":
            linker.declare(item.name, span)
            walls.setdefault(item.name, WallDecl(item.name, item.type or "wall", span))
        else:
            role: Role = {"StaticObject": "static", "DynamicObject": "dynamic",
                          "Human": "human", "Robot": "robot"}[kind]  # type: ignore[assignment]
            linker.declare(item.name, span)
            heading = None
            if item.heading is not None:
                heading = linker.number(item.heading.degrees, item.heading,
                                        f"heading of '{item.name}' (degrees)", low=-360.0,
                                        high=360.0)
            trajectory = _trajectory(linker, getattr(item, "trajectory", None), item.name)
            type_name = item.type or DEFAULT_TYPES.get(role, "")
            behaviour = _behaviour(linker, getattr(item, "behaviour", None), item.name)
            offset = linker.offset(getattr(item, "offset", None), f"offset of '{item.name}'")
            objects.append(PlacedObject(item.name, role, type_name, span, linker.ref(item.floor),
                                        heading, trajectory, span, behaviour, offset))

    neighbours = _resolve_links(linker, floors, walls)
    _resolve_placements(linker, floors, walls, objects)
    room = Room(
        name=textx_room.name,
        path=source.path,
        span=linker.span(textx_room),
        tile_size=tile if tile is not None else DEFAULT_TILE_SIZE,
        catalogue_path=catalogue_path,
        catalogue_span=catalogue_span,
        floors=MappingProxyType(floors),
        walls=MappingProxyType(walls),
        objects=tuple(objects),
        grids=tuple(grids),
        neighbours=MappingProxyType({k: MappingProxyType(v) for k, v in neighbours.items()}),
    )
    return room, linker.diagnostics


def _resolve_links(linker: _Linker, floors: dict[str, FloorDecl], walls: dict[str, WallDecl]
                   ) -> dict[str, dict[Side, str]]:
    blocks = set(floors) | set(walls)
    written: dict[str, dict[Side, NameRef]] = {name: {} for name in floors}
    for floor in floors.values():
        for side, ref in floor.links:
            if ref.name == floor.name:
                linker.error(ref.span, "LINK-SELF",
                             f"floor '{floor.name}': expected a neighbour other than itself on "
                             f"its {side.keyword} side, found '{ref.name}'")
                continue
            if ref.name not in blocks:
                if any(o for o in linker.declared if o == ref.name):
                    linker.error(ref.span, "REF-KIND",
                                 f"floor '{floor.name}': expected a floor or wall as its "
                                 f"{side.keyword} neighbour, found '{ref.name}', which is an "
                                 f"object")
                else:
                    linker.error(ref.span, "REF-UNRESOLVED",
                                 f"expected the name of a floor or wall, found '{ref.name}'"
                                 + did_you_mean(ref.name, blocks))
                continue
            written[floor.name][side] = ref
    effective: dict[str, dict[Side, str]] = {n: {s: r.name for s, r in links.items()}
                                             for n, links in written.items()}
    for name, links in written.items():
        for side, ref in links.items():
            if ref.name not in floors:
                continue
            back = written[ref.name].get(side.opposite)
            if back is None:
                effective[ref.name].setdefault(side.opposite, name)
            elif back.name != name:
                linker.error(ref.span, "LINK-ASYMMETRIC",
                             f"floor '{name}' has '{ref.name}' on its {side.keyword} side, so "
                             f"expected '{ref.name}' to have '{name}' on its "
                             f"{side.opposite.keyword} side, found '{back.name}'")
    # A reverse link implied twice for one side means two floors claim the same neighbour.
    return effective


def _resolve_placements(linker: _Linker, floors: dict[str, FloorDecl],
                        walls: dict[str, WallDecl], objects: list[PlacedObject]) -> None:
    for obj in objects:
        refs = [obj.floor]
        if obj.trajectory is not None:
            refs.extend(v.floor for v in obj.trajectory.vertices)
        trigger = obj.trajectory.trigger if obj.trajectory is not None else None
        if trigger is not None:
            refs.append(trigger.floor)
        for ref in refs:
            if ref.name in floors:
                continue
            what = ("to stand on" if ref is obj.floor else "to start the trajectory near"
                    if trigger is not None and ref is trigger.floor else "as a trajectory vertex")
            if ref.name in walls:
                linker.error(ref.span, "REF-KIND",
                             f"'{obj.name}': expected a floor {what}, found the wall "
                             f"'{ref.name}'")
            elif ref.name in linker.declared:
                linker.error(ref.span, "REF-KIND",
                             f"'{obj.name}': expected a floor {what}, found the object "
                             f"'{ref.name}'")
            else:
                linker.error(ref.span, "REF-UNRESOLVED",
                             f"expected the name of a floor, found '{ref.name}'"
                             + did_you_mean(ref.name, floors))
        traj = obj.trajectory
        if traj is not None and traj.vertices and traj.vertices[0].floor.name != obj.floor.name:
            first = traj.vertices[0]
            linker.error(first.span, "TRAJ-START",
                         f"trajectory of '{obj.name}': expected the first vertex to be its floor "
                         f"'{obj.floor.name}', found '{first.floor.name}'")
    robots = [o for o in objects if o.role == "robot"]
    for extra in robots[1:]:
        linker.error(extra.span, "ROBOT-COUNT",
                     f"expected exactly one robot, found '{extra.name}' as well as "
                     f"'{robots[0].name}'")
