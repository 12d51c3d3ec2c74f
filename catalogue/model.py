"""Typed records of the catalogue. Immutable; geometry in metres, mass in kg, angles in rad."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Literal

from rei.lang.errors import Diagnostic, LanguageError

Kind = Literal["floor", "wall", "static", "dynamic", "human", "robot"]
KINDS: tuple[Kind, ...] = ("floor", "wall", "static", "dynamic", "human", "robot")


class CatalogueError(LanguageError):
    """A catalogue file is not valid."""

    def __init__(self, diagnostics: list[Diagnostic]) -> None:
        super().__init__(diagnostics)


@dataclass(frozen=True)
class Box:
    """An axis-aligned rectangle in the object's frame: size along x and y."""

    size_x: float
    size_y: float

    def half_extents(self) -> tuple[float, float]:
        return self.size_x / 2, self.size_y / 2

    def circumradius(self) -> float:
        return math.hypot(self.size_x, self.size_y) / 2

    def inradius(self) -> float:
        return min(self.size_x, self.size_y) / 2


@dataclass(frozen=True)
class Cylinder:
    radius: float

    def half_extents(self) -> tuple[float, float]:
        return self.radius, self.radius

    def circumradius(self) -> float:
        return self.radius

    def inradius(self) -> float:
        return self.radius


@dataclass(frozen=True)
class Polygon:
    """A convex or simple polygon, counter-clockwise, in the object's frame."""

    points: tuple[tuple[float, float], ...]

    def half_extents(self) -> tuple[float, float]:
        xs = [p[0] for p in self.points]
        ys = [p[1] for p in self.points]
        return max(abs(v) for v in xs), max(abs(v) for v in ys)

    def circumradius(self) -> float:
        return max(math.hypot(x, y) for x, y in self.points)

    def inradius(self) -> float:
        hx, hy = self.half_extents()
        return min(hx, hy)


@dataclass(frozen=True)
class Tile:
    """The footprint of floors and walls: one cell of the room's tile size."""

    def half_extents(self) -> tuple[float, float]:
        raise TypeError("a tile footprint takes its size from the room")

    def circumradius(self) -> float:
        raise TypeError("a tile footprint takes its size from the room")

    def inradius(self) -> float:
        raise TypeError("a tile footprint takes its size from the room")


Footprint = Box | Cylinder | Polygon | Tile


@dataclass(frozen=True)
class DriveSpec:
    """Differential drive limits: speeds, and the accelerations its commands may ask for (all
    positive magnitudes; the defaults are Nav2's velocity smoother's, so a catalogue written
    before they existed still loads)."""

    max_linear: float
    max_angular: float
    wheel_separation: float
    wheel_radius: float
    max_linear_accel: float = 2.5
    """m/s^2 the linear command may rise by per second (speeding up, either direction)."""
    max_linear_decel: float = 2.5
    """m/s^2 the linear command may fall by per second (slowing down towards standstill)."""
    max_angular_accel: float = 3.2
    """rad/s^2 the angular command may rise by per second."""
    max_angular_decel: float = 3.2
    """rad/s^2 the angular command may fall by per second."""


@dataclass(frozen=True)
class LaserSpec:
    """A planar laser scanner, beams spread evenly over ``fov`` starting at ``-fov/2``."""

    beams: int
    min_range: float
    max_range: float
    rate: float
    fov: float
    mount_x: float = 0.0
    mount_y: float = 0.0
    mount_z: float = 0.1
    noise: float = 0.0
    """Standard deviation (m) of the Gaussian error of every range that hit something."""


@dataclass(frozen=True)
class ObjectType:
    name: str
    kind: Kind
    footprint: Footprint
    height: float
    mass: float
    inertia: tuple[float, float, float]
    colour: tuple[float, float, float, float]
    mesh: str | None = None
    drive: DriveSpec | None = None
    laser: LaserSpec | None = None
    description: str = ""


@dataclass(frozen=True)
class Catalogue:
    types: Mapping[str, ObjectType] = field(default_factory=lambda: MappingProxyType({}))
    sources: tuple[str, ...] = ()

    def get(self, name: str) -> ObjectType | None:
        return self.types.get(name)

    def names(self, kind: Kind | None = None) -> list[str]:
        return sorted(n for n, t in self.types.items() if kind is None or t.kind == kind)

    def merged(self, other: Catalogue) -> Catalogue:
        """This catalogue with ``other``'s types added, replacing same-named ones."""
        types = dict(self.types)
        types.update(other.types)
        return Catalogue(MappingProxyType(types), self.sources + other.sources)


def solid_inertia(footprint: Footprint, height: float, mass: float) -> tuple[float, float, float]:
    """Principal moments (ixx, iyy, izz) of a uniform solid of this footprint and height."""
    if isinstance(footprint, Cylinder):
        r = footprint.radius
        side = mass * (3 * r * r + height * height) / 12
        return side, side, mass * r * r / 2
    if isinstance(footprint, Tile):
        return 0.0, 0.0, 0.0
    hx, hy = footprint.half_extents()
    # Polygons are approximated by their bounding box: close enough for furniture.
    sx, sy = 2 * hx, 2 * hy
    return (
        mass * (sy * sy + height * height) / 12,
        mass * (sx * sx + height * height) / 12,
        mass * (sx * sx + sy * sy) / 12,
    )
