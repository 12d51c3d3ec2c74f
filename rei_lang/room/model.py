"""Typed, immutable abstract model of a room (thesis Figure 10), built by the linker.

Names stay names here (a floor's neighbour is the *name* of a building block); the linker
has checked that every name resolves, and the layout gives each block its cell.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from enum import Enum
from typing import Literal

from rei.lang.errors import Span

DEFAULT_TILE_SIZE = 1.0
Role = Literal["static", "dynamic", "human", "robot"]
Behaviour = Literal["scripted", "yielding", "social"]
BEHAVIOURS: tuple[Behaviour, ...] = ("scripted", "yielding", "social")
"""How a human reacts to the robot (runtime/simulation/animator/): ``scripted`` walks its
spline regardless, ``yielding`` waits while the robot is in its way, ``social`` is pushed
around it by a social force. ``scripted`` is the default so hand-written rooms keep the
thesis's behaviour."""
DEFAULT_BEHAVIOUR: Behaviour = "scripted"
WALKING_SPEEDS = (0.5, 1.4)
"""m/s: the range of human walking speeds (generated rooms and seeded variations keep
humans in it; a hand-written trajectory may leave it)."""


class Side(Enum):
    """A floor's sides; +x is RIGHT and +y is TOP (a grid's first row is its top)."""

    TOP = (0, 1)
    RIGHT = (1, 0)
    BOTTOM = (0, -1)
    LEFT = (-1, 0)

    @property
    def delta(self) -> tuple[int, int]:
        return self.value

    @property
    def opposite(self) -> Side:
        dx, dy = self.value
        return Side((-dx, -dy))

    @property
    def keyword(self) -> str:
        return self.name.lower()


@dataclass(frozen=True)
class NameRef:
    """A name written in a file, where it was written."""

    name: str
    span: Span


@dataclass(frozen=True)
class GridCell:
    grid: str
    row: int
    col: int


@dataclass(frozen=True)
class FloorDecl:
    name: str
    type: str
    span: Span
    links: tuple[tuple[Side, NameRef], ...]
    cell_of_grid: GridCell | None = None


@dataclass(frozen=True)
class WallDecl:
    name: str
    type: str
    span: Span
    cell_of_grid: GridCell | None = None


@dataclass(frozen=True)
class Vertex:
    floor: NameRef
    time: float | None
    span: Span
    offset: tuple[float, float] = (0.0, 0.0)
    """Metres (x, y) from the floor's centre (``offset DX DY``)."""


@dataclass(frozen=True)
class StartTrigger:
    """`when robot within DISTANCE of FLOOR`: the trajectory's clock starts when the
    robot's centre first comes within ``distance`` metres of the floor's centre."""

    floor: NameRef
    distance: float
    span: Span


@dataclass(frozen=True)
class Trajectory:
    vertices: tuple[Vertex, ...]
    total_time: float | None
    loop: bool
    span: Span
    trigger: StartTrigger | None = None
    """None: the clock starts with the run."""


@dataclass(frozen=True)
class PlacedObject:
    """A static object, dynamic object, human or robot standing on a floor (at its centre,
    unless a static object's or a human's ``offset`` moves it within the tile)."""

    name: str
    role: Role
    type: str
    type_span: Span
    floor: NameRef
    heading_deg: float | None
    trajectory: Trajectory | None
    span: Span
    behaviour: Behaviour = DEFAULT_BEHAVIOUR
    """Humans only; every other role is moved by its trajectory alone."""
    offset: tuple[float, float] = (0.0, 0.0)
    """Metres (x, y) from the floor's centre (``offset DX DY``: static objects
    and humans, whose first trajectory vertex is usually where they stand)."""


@dataclass(frozen=True)
class GridDecl:
    name: str
    span: Span
    rows: tuple[str, ...]
    row_spans: tuple[Span, ...]
    cells: Mapping[tuple[int, int], str]
    """(row, col) → the name of the floor or wall in that cell."""


@dataclass(frozen=True)
class Room:
    name: str
    path: str
    span: Span
    tile_size: float
    catalogue_path: str | None
    catalogue_span: Span | None
    floors: Mapping[str, FloorDecl]
    walls: Mapping[str, WallDecl]
    objects: tuple[PlacedObject, ...]
    grids: tuple[GridDecl, ...]
    neighbours: Mapping[str, Mapping[Side, str]]
    """Every floor's effective neighbours: links as written, completed by their reverse."""

    @property
    def robot(self) -> PlacedObject | None:
        robots = [o for o in self.objects if o.role == "robot"]
        return robots[0] if robots else None

    def objects_on(self, floor: str) -> list[PlacedObject]:
        return [o for o in self.objects if o.floor.name == floor]

    def declaration_span(self, name: str) -> Span | None:
        if name in self.floors:
            return self.floors[name].span
        if name in self.walls:
            return self.walls[name].span
        for obj in self.objects:
            if obj.name == name:
                return obj.span
        return None
