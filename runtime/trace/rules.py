"""The rules of a trace line's fields, one set for the reader and the writer: the checks of
one field (``_number``, ``_numbers``, ``_Fields``; every error located as ``path:line:
field: expected ..., found ...``) and the header's rules (objects, footprints, floors,
mission facts, collected data, faults). The rules between the lines (samples, the end line)
are ``sample_rules``. This module only checks: it never encodes, opens or writes a file,
must never import ``encode`` or ``read``, nor the simulation or pybullet.
"""

from __future__ import annotations

import math
import sys
from typing import Any

from rei.catalogue import Box, Cylinder, Footprint, Polygon, Tile
from rei.lang.mission.faults import fault_name_problem
from rei.lang.mission.model import COLLECTED_DATA, REQUIRED_DATA
from rei.runtime.messages import (
    OBJECT_ROLES,
    SCHEMA_VERSION,
    GoalFacts,
    MissionFacts,
    ObservedObject,
    StreamHeader,
)
from rei.runtime.trace.format import FORMAT, PREVIOUS_SCHEMA, TRACE_VERSION, TraceError

# ---- the rules: one set for the reader and the writer ----------------------------------------

_HEADER_KEYS = frozenset(("format", "trace_version", "version", "world", "mission", "seed",
                          "rate", "robot", "objects", "tile_size", "floors", "laser_mount",
                          "mission_facts", "data"))
_OBJECT_KEYS = frozenset(("name", "role", "type", "footprint", "height"))
_FOOTPRINT_KEYS = {"box": frozenset(("shape", "size")),
                   "cylinder": frozenset(("shape", "radius")),
                   "polygon": frozenset(("shape", "points")), "tile": frozenset(("shape",))}
_FACTS_KEYS = frozenset(("goals", "cycles", "time_limit", "speed_limit", "turn_limit",
                         "mission_max_speed"))
COMMAND_LIMITS = ("accel_limit", "decel_limit", "turn_accel_limit", "turn_decel_limit")
"""The mission facts' command acceleration limits: all four or none (a trace recorded before
REI carried them; the limits then read as unknown, inf)."""
_GOAL_KEYS = frozenset(("name", "x", "y", "heading", "tolerance", "heading_tolerance",
                        "timeout"))
_FAULT_KEYS = frozenset(("name", "entry"))
_FLOATS = frozenset((float,))
_COUNTS = {2: "two", 3: "three"}


def _show(value: Any) -> str:
    """A found value for a message: its repr, cut short (a damaged line can be megabytes)."""
    try:
        text = repr(value)
    except ValueError:  # an int of more digits than Python converts to text
        return "a number too large to show"
    return text if len(text) <= 80 else text[:77] + "..."


def _fmt(x: float) -> str:
    return f"{x:.10g}"


def _at(where: str, field: str) -> str:
    return f"{where}: {field}" if field else where


def _is_number(value: Any) -> bool:
    """A finite JSON number; a bool is not one, nor an int too large for a float."""
    if isinstance(value, float):
        return math.isfinite(value)
    return isinstance(value, int) and not isinstance(value, bool) \
        and abs(value) <= sys.float_info.max


def _is_whole(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _range_text(low: float, high: float, low_open: bool, note: str) -> str:
    bounds = []
    if math.isfinite(low):
        bounds.append(f"{'>' if low_open else '>='} {_fmt(low)}")
    if math.isfinite(high):
        bounds.append(f"<= {_fmt(high)}")
    return " and ".join(bounds) + (f" {note}" if note else "")


def _number(value: Any, where: str, field: str, low: float = -math.inf,
            high: float = math.inf, low_open: bool = False, note: str = "") -> float:
    """``value`` as a finite number in its range, else a located error."""
    if _is_number(value) and (value > low if low_open else value >= low) and value <= high:
        return float(value)
    expected = " ".join(("a finite number", _range_text(low, high, low_open, note))).strip()
    raise TraceError(f"{_at(where, field)}: expected {expected}, found {_show(value)}")


def _numbers(value: Any, where: str, field: str, n: int, form: str, low: float = -math.inf,
             low_open: bool = False) -> tuple[float, ...]:
    """Exactly ``n`` finite numbers (above ``low``, when given): a pose, a twist, a size."""
    # the common case first, as cheap as it gets: floats only, finite, no bound
    if type(value) is list and len(value) == n and low == -math.inf \
            and _FLOATS.issuperset(map(type, value)) and all(map(math.isfinite, value)):
        return tuple(value)
    if isinstance(value, list) and len(value) == n and all(
            _is_number(v) and (v > low if low_open else v >= low) for v in value):
        return tuple(float(v) for v in value)
    bound = _range_text(low, math.inf, low_open, "")
    raise TraceError(f"{_at(where, field)}: expected {_COUNTS.get(n, str(n))} finite numbers"
                     f"{' ' + bound if bound else ''} {form}, found {_show(value)}")


class _Fields:
    """One JSON object of a trace line, its fields taken out checked; every error names the
    line (``where``) and the field's path from the line (``prefix.key``)."""

    __slots__ = ("data", "prefix", "where")

    def __init__(self, data: Any, where: str, prefix: str, keys: frozenset[str],
                 what: str) -> None:
        if not isinstance(data, dict):
            raise TraceError(f"{_at(where, prefix)}: expected {what}, found {_show(data)}")
        if data.keys() != keys:
            missing = sorted(keys - data.keys())
            if missing:
                raise TraceError(f"{_at(where, prefix)}: expected {what} with the field "
                                 f"'{missing[0]}', found none")
            unknown = sorted(data.keys() - keys)
            allowed = f"only the fields {', '.join(sorted(keys))}" if keys else "no fields"
            raise TraceError(f"{_at(where, prefix)}: expected {allowed}, found the unknown "
                             f"field {_show(unknown[0])}")
        self.data: dict[str, Any] = data
        self.where = where
        self.prefix = prefix

    def field(self, key: str) -> str:
        return f"{self.prefix}.{key}" if self.prefix else key

    def number(self, key: str, low: float = -math.inf, high: float = math.inf,
               low_open: bool = False, note: str = "") -> float:
        value = self.data[key]
        # the common case, a float in range, before the field's path is even spelt out
        if type(value) is float and (value > low if low_open else value >= low) \
                and value <= high and math.isfinite(value):
            return value
        return _number(value, self.where, self.field(key), low, high, low_open, note)

    def optional_number(self, key: str, **bounds: Any) -> float | None:
        return None if self.data[key] is None else self.number(key, **bounds)

    def numbers(self, key: str, n: int, form: str, **bounds: Any) -> tuple[float, ...]:
        value = self.data[key]
        # the common case (``_numbers``' first), before the field's path is even spelt out
        if not bounds and type(value) is list and len(value) == n \
                and _FLOATS.issuperset(map(type, value)) and all(map(math.isfinite, value)):
            return tuple(value)
        return _numbers(value, self.where, self.field(key), n, form, **bounds)

    def whole(self, key: str, low: int) -> int:
        value = self.data[key]
        if _is_whole(value) and value >= low:
            return int(value)
        raise TraceError(f"{self.where}: {self.field(key)}: expected a whole number >= {low}, "
                         f"found {_show(value)}")

    def text(self, key: str) -> str:
        value = self.data[key]
        if isinstance(value, str):
            return value
        raise TraceError(f"{self.where}: {self.field(key)}: expected a string, found "
                         f"{_show(value)}")

    def optional_text(self, key: str) -> str | None:
        value = self.data[key]
        if value is None or isinstance(value, str):
            return value
        raise TraceError(f"{self.where}: {self.field(key)}: expected a string or null, found "
                         f"{_show(value)}")

    def choice(self, key: str, allowed: tuple[str, ...], note: str = "") -> str:
        value = self.data[key]
        if isinstance(value, str) and value in allowed:
            return value
        raise TraceError(f"{self.where}: {self.field(key)}: expected one of "
                         f"{', '.join(map(repr, allowed))}{note}, found {_show(value)}")

    def fields(self, key: str, keys: frozenset[str], what: str) -> _Fields:
        return _Fields(self.data[key], self.where, self.field(key), keys, what)

    def array(self, key: str, what: str) -> list[Any]:
        value = self.data[key]
        if isinstance(value, list):
            return value
        raise TraceError(f"{self.where}: {self.field(key)}: expected a list of {what}, found "
                         f"{_show(value)}")


def footprint_of(value: Any, where: str, field: str, robot: bool = False,
                 shapes: tuple[str, ...] | None = None) -> Footprint:
    """The footprint a JSON value encodes (rei.catalogue.codec's encoding), every field checked;
    TraceError naming ``where: field``, what was expected and what was found. ``shapes`` limits
    the shapes accepted (the generated world files hold only what the simulator builds)."""
    if shapes is None:
        shapes = tuple(s for s in _FOOTPRINT_KEYS if not (robot and s == "tile"))
    shape = value.get("shape") if isinstance(value, dict) else None
    if shape not in shapes:
        if not isinstance(value, dict):
            raise TraceError(f"{where}: {field}: expected a footprint (a JSON object), found "
                             f"{_show(value)}")
        raise TraceError(f"{where}: {field}.shape: expected one of {', '.join(map(repr, shapes))}"
                         f"{' (a robot has its own footprint)' if robot else ''}, found "
                         f"{_show(shape)}")
    f = _Fields(value, where, field, _FOOTPRINT_KEYS[shape], f"a {shape} footprint")
    if shape == "box":
        x, y = f.numbers("size", 2, "[size_x, size_y]", low=0.0, low_open=True)
        return Box(x, y)
    if shape == "cylinder":
        return Cylinder(f.number("radius", low=0.0, low_open=True))
    if shape == "polygon":
        points = f.data["points"]
        if isinstance(points, list) and len(points) >= 3 and all(
                isinstance(p, list) and len(p) == 2 and all(map(_is_number, p)) for p in points):
            pts = tuple((float(p[0]), float(p[1])) for p in points)
            # the shoelace area: a polygon of no area is a footprint nothing can touch
            area = sum(a[0] * b[1] - b[0] * a[1] for a, b in zip(pts, pts[1:] + pts[:1],
                                                                  strict=True))
            if area != 0.0:
                return Polygon(pts)
        raise TraceError(f"{where}: {field}.points: expected at least three [x, y] points of "
                         f"finite numbers enclosing an area, found {_show(points)}")
    return Tile()


def observed_object_of(value: Any, where: str, field: str, robot: bool = False,
                       shapes: tuple[str, ...] | None = None) -> ObservedObject:
    """The observed object a JSON value encodes (name, role, type, footprint, height), every
    field checked, as ``footprint_of`` checks its footprint."""
    o = _Fields(value, where, field, _OBJECT_KEYS, "an observed object (a JSON object)")
    return ObservedObject(o.text("name"), o.choice("role", OBJECT_ROLES),  # type: ignore[arg-type]
                          o.text("type"), footprint_of(o.data["footprint"], where,
                                                       o.field("footprint"), robot, shapes),
                          o.number("height", low=0.0))


def _floor(value: Any, where: str, field: str) -> tuple[str, float, float]:
    if isinstance(value, list) and len(value) == 3 and isinstance(value[0], str) \
            and _is_number(value[1]) and _is_number(value[2]):
        return value[0], float(value[1]), float(value[2])
    raise TraceError(f"{where}: {field}: expected [name, x, y] with two finite numbers, found "
                     f"{_show(value)}")


def _mission_facts(value: Any, where: str) -> MissionFacts | None:
    """The header's mission facts, every number checked: a requirement reading a NaN goal or
    a zero speed limit would give verdicts about nothing."""
    if value is None:
        return None
    limits = isinstance(value, dict) and any(key in value for key in COMMAND_LIMITS)
    f = _Fields(value, where, "mission_facts",
                _FACTS_KEYS | frozenset(COMMAND_LIMITS) if limits else _FACTS_KEYS,
                "the mission's facts (a JSON object, or null)")
    raw = f.array("goals", "goals")
    if not raw:
        raise TraceError(f"{where}: mission_facts.goals: expected at least one goal, found none")
    goals = []
    for i, item in enumerate(raw):
        g = _Fields(item, where, f"mission_facts.goals[{i}]", _GOAL_KEYS,
                    "a goal (a JSON object)")
        goals.append(GoalFacts(
            g.text("name"), g.number("x"), g.number("y"),
            g.optional_number("heading", low=-math.pi, high=math.pi),
            g.number("tolerance", low=0.0, low_open=True),
            g.number("heading_tolerance", low=0.0, low_open=True, high=math.pi),
            g.number("timeout", low=0.0, low_open=True)))
    positive: dict[str, Any] = {"low": 0.0, "low_open": True}
    return MissionFacts(tuple(goals), f.whole("cycles", 1),
                        f.number("time_limit", **positive), f.number("speed_limit", **positive),
                        f.number("turn_limit", **positive),
                        f.optional_number("mission_max_speed", **positive),
                        *(f.number(key, **positive) if limits else math.inf
                          for key in COMMAND_LIMITS))


def _header(data: Any, where: str) -> StreamHeader:
    if not isinstance(data, dict):
        raise TraceError(f"{where}: expected a REI trace header (a JSON object), found "
                         f"{_show(data)}")
    if data.get("format") != FORMAT:
        raise TraceError(f"{where}: format: expected a REI trace ('{FORMAT}'), found "
                         f"{_show(data.get('format'))}")
    schema = data.get("version")
    if data.get("trace_version") != TRACE_VERSION or not (
            schema in (SCHEMA_VERSION, PREVIOUS_SCHEMA) and _is_whole(schema)):
        raise TraceError(f"{where}: expected trace version {TRACE_VERSION} with sample schema "
                         f"{SCHEMA_VERSION} (or {PREVIOUS_SCHEMA}), found "
                         f"{data.get('trace_version')!r} with schema {schema!r} (record it "
                         f"again with this REI)")
    previous = schema == PREVIOUS_SCHEMA
    keys = _HEADER_KEYS - {"data"} if previous else _HEADER_KEYS
    h = _Fields(data, where, "", keys | {"faults"} if "faults" in data and not previous
                else keys, "a REI trace header")
    objects = h.array("objects", "observed objects")
    floors = h.array("floors", "floors")
    laser_mount = h.numbers("laser_mount", 2, "[x, y]")
    return StreamHeader(
        SCHEMA_VERSION, h.text("world"), h.text("mission"), h.whole("seed", 0),
        h.number("rate", low=0.0, low_open=True),
        observed_object_of(data["robot"], where, "robot", True),
        tuple(observed_object_of(o, where, f"objects[{i}]") for i, o in enumerate(objects)),
        h.number("tile_size", low=0.0, low_open=True),
        tuple(_floor(f, where, f"floors[{i}]") for i, f in enumerate(floors)),
        (laser_mount[0], laser_mount[1]), _mission_facts(data["mission_facts"], where),
        COLLECTED_DATA if previous else _data(data["data"], where),
        _faults(data["faults"], where) if "faults" in data else ())


def _faults(value: Any, where: str) -> tuple[tuple[str, str], ...]:
    """The header's injected faults: a non-empty list of {name, entry}, names unique."""
    if not (isinstance(value, list) and value):
        raise TraceError(f"{where}: faults: expected a non-empty list of the injected faults "
                         f"(absent when there are none), found {_show(value)}")
    faults: list[tuple[str, str]] = []
    for i, item in enumerate(value):
        f = _Fields(item, where, f"faults[{i}]", _FAULT_KEYS, "a fault (a JSON object)")
        name = f.text("name")
        wrong = fault_name_problem(name)
        if wrong is not None:  # as `rei run` names them: events.csv joins them with ';'
            raise TraceError(f"{where}: faults[{i}].name: {wrong}")
        if any(name == n for n, _ in faults):
            raise TraceError(f"{where}: faults[{i}].name: expected a name no other fault has, "
                             f"found {_show(name)}")
        faults.append((name, f.text("entry")))
    return tuple(faults)


def _data(value: Any, where: str) -> tuple[str, ...]:
    """The header's collected data: known names, each once, the required ones among them."""
    if not (isinstance(value, list) and all(isinstance(n, str) for n in value)):
        raise TraceError(f"{where}: data: expected a list of the names "
                         f"{', '.join(COLLECTED_DATA)}, found {_show(value)}")
    for i, name in enumerate(value):
        if name not in COLLECTED_DATA or name in value[:i]:
            which = "another" if name in value[:i] else "one"
            raise TraceError(f"{where}: data[{i}]: expected {which} of "
                             f"{', '.join(COLLECTED_DATA)}, found {_show(name)}")
    for name in REQUIRED_DATA:
        if name not in value:
            raise TraceError(f"{where}: data: expected {name!r} among the collected data, "
                             f"found {_show(value)}")
    return tuple(d for d in COLLECTED_DATA if d in value)
