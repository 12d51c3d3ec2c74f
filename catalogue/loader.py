"""Reading catalogue TOML files into typed records, with errors that name the field."""

from __future__ import annotations

import functools
import math
import re
import tomllib
from importlib import resources
from pathlib import Path
from types import MappingProxyType
from typing import Any

from rei.catalogue.model import (
    KINDS,
    Box,
    Catalogue,
    CatalogueError,
    Cylinder,
    DriveSpec,
    Footprint,
    LaserSpec,
    ObjectType,
    Polygon,
    Tile,
    solid_inertia,
)
from rei.lang.errors import Diagnostic, Span
from rei.lang.parsing import deepest_nesting
from rei.lang.source import SourceText, read_source
from rei.lang.suggest import did_you_mean

_TYPE_FIELDS = {"kind", "description", "footprint", "height", "mass", "inertia", "colour",
                "mesh", "drive", "laser"}
_DRIVE_FIELDS = {"max_linear", "max_angular", "wheel_separation", "wheel_radius",
                 "max_linear_accel", "max_linear_decel", "max_angular_accel",
                 "max_angular_decel"}
_ACCELERATIONS = {"max_linear_accel": DriveSpec.max_linear_accel,
                  "max_linear_decel": DriveSpec.max_linear_decel,
                  "max_angular_accel": DriveSpec.max_angular_accel,
                  "max_angular_decel": DriveSpec.max_angular_decel}
"""The drive's optional fields and their defaults (Nav2's velocity smoother's)."""
_MAX_DIMENSION = 1000.0
_MAX_MASS = 1.0e6


class _Reader:
    """Collects every problem of one catalogue file, each located by field path and line."""

    def __init__(self, path: str, text: str) -> None:
        self.path = path
        self.text = text
        self.diagnostics: list[Diagnostic] = []

    def _line_of(self, type_name: str) -> int:
        match = re.search(rf"^[ \t]*\[types\.{re.escape(type_name)}[\].]", self.text, re.MULTILINE)
        return self.text.count("\n", 0, match.start()) + 1 if match else 1

    def error(self, type_name: str, field: str, expected: str, found: Any) -> None:
        shown = repr(found) if not isinstance(found, str) else f"'{found}'"
        self.diagnostics.append(
            Diagnostic(
                Span.point(self.path, self._line_of(type_name)),
                "CATALOGUE-FIELD",
                f"types.{type_name}.{field}: expected {expected}, found {shown}",
            )
        )

    def number(self, tname: str, field: str, value: Any, *, low: float, high: float,
               low_open: bool = False, integer: bool = False) -> float:
        ok = isinstance(value, (int, float)) and not isinstance(value, bool)
        if ok and integer and not float(value).is_integer():
            ok = False
        if ok:
            v = float(value)
            ok = math.isfinite(v) and (v > low if low_open else v >= low) and v <= high
        if not ok:
            bound = f"{'>' if low_open else '>='} {low:g} and <= {high:g}"
            self.error(tname, field, f"a finite {'whole ' if integer else ''}number {bound}", value)
            return max(low, 1.0) if not low_open else max(low * 2, 1.0)
        return float(value)

    def vector(self, tname: str, field: str, value: Any, n: int, low: float, high: float
               ) -> tuple[float, ...]:
        if not isinstance(value, list) or len(value) != n:
            self.error(tname, field, f"a list of {n} numbers", value)
            return tuple([low] * n)
        return tuple(self.number(tname, f"{field}[{i}]", v, low=low, high=high)
                     for i, v in enumerate(value))

    def footprint(self, tname: str, value: Any) -> Footprint:
        if not isinstance(value, dict):
            self.error(tname, "footprint", "a table with a 'shape'", value)
            return Tile()
        shape = value.get("shape")
        if shape == "tile":
            return Tile()
        if shape == "box":
            sx, sy = self.vector(tname, "footprint.size", value.get("size"), 2, 1e-3,
                                 _MAX_DIMENSION)
            return Box(sx, sy)
        if shape == "cylinder":
            r = self.number(tname, "footprint.radius", value.get("radius"), low=1e-3,
                            high=_MAX_DIMENSION)
            return Cylinder(r)
        if shape == "polygon":
            pts = value.get("points")
            if not isinstance(pts, list) or len(pts) < 3:
                self.error(tname, "footprint.points", "a list of at least 3 [x, y] points", pts)
                return Box(1.0, 1.0)
            points = tuple(
                self.vector(tname, f"footprint.points[{i}]", p, 2, -_MAX_DIMENSION, _MAX_DIMENSION)
                for i, p in enumerate(pts)
            )
            return Polygon(tuple((p[0], p[1]) for p in points))
        self.error(tname, "footprint.shape", "one of 'box', 'cylinder', 'polygon', 'tile'", shape)
        return Tile()

    def object_type(self, tname: str, raw: Any) -> ObjectType | None:
        if not isinstance(raw, dict):
            self.error(tname, "", "a table of fields", raw)
            return None
        for key in raw:
            if key not in _TYPE_FIELDS:
                self.error(tname, key, "a known field" + did_you_mean(key, _TYPE_FIELDS), key)
        kind = raw.get("kind")
        if kind not in KINDS:
            self.error(tname, "kind", "one of " + ", ".join(KINDS), kind)
            return None
        footprint = self.footprint(tname, raw.get("footprint"))
        if isinstance(footprint, Tile) and kind not in ("floor", "wall"):
            self.error(tname, "footprint.shape", "'box', 'cylinder' or 'polygon' for a "
                       f"{kind} type (only floors and walls take the tile)", "tile")
        height = self.number(tname, "height", raw.get("height"), low=0.0, high=_MAX_DIMENSION,
                             low_open=True)
        mass = self.number(tname, "mass", raw.get("mass", 0.0), low=0.0, high=_MAX_MASS)
        if kind in ("dynamic", "human", "robot") and mass <= 0:
            self.error(tname, "mass", f"a positive mass for a {kind} type", raw.get("mass"))
        if "inertia" in raw:
            ixx, iyy, izz = self.vector(tname, "inertia", raw["inertia"], 3, 0.0, _MAX_MASS)
            inertia = (ixx, iyy, izz)
        else:
            inertia = solid_inertia(footprint, height, mass)
        r, g, b, a = self.vector(tname, "colour", raw.get("colour", [0.7, 0.7, 0.7, 1.0]), 4,
                                 0.0, 1.0)
        mesh = raw.get("mesh")
        if mesh is not None and not isinstance(mesh, str):
            self.error(tname, "mesh", "a file path string", mesh)
            mesh = None
        drive = laser = None
        if kind == "robot":
            drive = self.drive(tname, raw.get("drive"))
            laser = self.laser(tname, raw.get("laser"))
        description = raw.get("description", "")
        return ObjectType(tname, kind, footprint, height, mass, inertia, (r, g, b, a),
                          mesh, drive, laser, description if isinstance(description, str) else "")

    def drive(self, tname: str, raw: Any) -> DriveSpec | None:
        if not isinstance(raw, dict):
            self.error(tname, "drive", "a table with max_linear, max_angular, wheel_separation, "
                       "wheel_radius", raw)
            return None
        for key in raw:
            if key not in _DRIVE_FIELDS:
                self.error(tname, f"drive.{key}",
                           "a known field" + did_you_mean(key, _DRIVE_FIELDS), key)
        return DriveSpec(
            max_linear=self.number(tname, "drive.max_linear", raw.get("max_linear"), low=0.0,
                                   high=100.0, low_open=True),
            max_angular=self.number(tname, "drive.max_angular", raw.get("max_angular"), low=0.0,
                                    high=100.0, low_open=True),
            wheel_separation=self.number(tname, "drive.wheel_separation",
                                         raw.get("wheel_separation"), low=0.0, high=100.0,
                                         low_open=True),
            wheel_radius=self.number(tname, "drive.wheel_radius", raw.get("wheel_radius"),
                                     low=0.0, high=100.0, low_open=True),
            **{key: self.number(tname, f"drive.{key}", raw.get(key, default), low=0.0,
                                high=1000.0, low_open=True)
               for key, default in _ACCELERATIONS.items()},
        )

    def laser(self, tname: str, raw: Any) -> LaserSpec | None:
        if not isinstance(raw, dict):
            self.error(tname, "laser", "a table with beams, min_range, max_range, rate, fov", raw)
            return None
        beams = int(self.number(tname, "laser.beams", raw.get("beams"), low=1, high=100_000,
                                integer=True))
        lo = self.number(tname, "laser.min_range", raw.get("min_range"), low=0.0, high=1000.0)
        hi = self.number(tname, "laser.max_range", raw.get("max_range"), low=0.0, high=1000.0,
                         low_open=True)
        if hi <= lo:
            self.error(tname, "laser.max_range", f"a range above min_range ({lo:g})", hi)
        rate = self.number(tname, "laser.rate", raw.get("rate"), low=0.0, high=1000.0,
                           low_open=True)
        fov = self.number(tname, "laser.fov", raw.get("fov", 360.0), low=0.0, high=360.0,
                          low_open=True)
        mx, my, mz = self.vector(tname, "laser.mount", raw.get("mount", [0.0, 0.0, 0.1]), 3,
                                 -100.0, 100.0)
        noise = self.number(tname, "laser.noise", raw.get("noise", 0.0), low=0.0, high=1.0)
        return LaserSpec(beams, lo, hi, rate, math.radians(fov), mx, my, mz, noise)


def parse_catalogue(path: str, text: str) -> Catalogue:
    """A catalogue from TOML text; raises CatalogueError with every problem found."""
    try:
        data = tomllib.loads(text)
    except RecursionError:  # tomllib nests arrays and inline tables by recursion
        depth, offset = deepest_nesting(text)
        line, col = SourceText(path, text).line_col(offset)
        raise CatalogueError([Diagnostic(
            Span.point(path, line, col), "CATALOGUE-SYNTAX",
            f"expected arrays and tables nested less deeply, found {depth} levels here")]
        ) from None
    except tomllib.TOMLDecodeError as exc:
        match = re.search(r"\(at line (\d+), column (\d+)\)", str(exc))
        line, col = (int(match.group(1)), int(match.group(2))) if match else (1, 1)
        message = re.sub(r"\s*\(at line.*\)", "", str(exc))
        raise CatalogueError(
            [Diagnostic(Span.point(path, line, col), "CATALOGUE-SYNTAX",
                        f"expected valid TOML, found a problem: {message}")]
        ) from None
    reader = _Reader(path, text)
    unknown = [k for k in data if k != "types"]
    for key in unknown:
        reader.diagnostics.append(Diagnostic(
            Span.point(path), "CATALOGUE-FIELD",
            f"{key}: expected only a [types.NAME] table per type, found '{key}'"))
    raw_types = data.get("types", {})
    types: dict[str, ObjectType] = {}
    if not isinstance(raw_types, dict):
        reader.error("", "types", "tables [types.NAME]", raw_types)
        raw_types = {}
    for name, raw in raw_types.items():
        if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name):
            reader.error(name, "", "a type name of letters, digits and '_'", name)
            continue
        obj = reader.object_type(name, raw)
        if obj is not None:
            types[name] = obj
    if reader.diagnostics:
        raise CatalogueError(reader.diagnostics)
    return Catalogue(MappingProxyType(types), (path,))


@functools.cache
def default_catalogue() -> Catalogue:
    """The catalogue that ships with REI (parsed once per process; it is immutable)."""
    ref = resources.files("rei.catalogue").joinpath("default.toml")
    return parse_catalogue("<default catalogue>", ref.read_text(encoding="utf-8"))


def load_catalogue(path: str | Path | None) -> Catalogue:
    """The default catalogue, merged with a user's catalogue file when one is given."""
    base = default_catalogue()
    if path is None:
        return base
    source = read_source(path)
    if isinstance(source, Diagnostic):
        raise CatalogueError([source])
    return base.merged(parse_catalogue(source.path, source.text))
