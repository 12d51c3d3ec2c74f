"""The run's sample trace on disk: exact, deterministic JSON lines, and reading it back.

Line 1 is the stream header, then one line per sample, then an ``end`` line with the
outcome. Floats are written by ``repr`` (Python's shortest round-tripping form), so reading
a trace gives back bit-identical numbers. Per-object poses and twists are written as the
rows that changed since the previous sample (static objects appear once), which keeps a
trace of a room of walls small without losing exactness. The writer streams to
``NAME.partial`` and renames it into place at ``finish``: a trace file that exists is
complete; a killed run leaves only the partial file.

A recording is input like any other: the reader checks every field of every line (JSON
types, with a bool never a number; finite numbers in their ranges; sequence numbers 0, 1, 2,
... without gaps; times that never go back; known event kinds, outcomes and causes; object
indices within the header's table; a sample carrying exactly the data the header names as
collected; exactly one end line, last) and refuses the first
violation with a ``TraceError`` naming ``path:line: field: expected ..., found ...``. The
reader stays lazy: a damaged line 5000 is found when line 5000 is read. The writer applies
the same rules to what it is about to write, so whatever it writes reads back and it never
writes what the reader would refuse. Traces of sample schema 3 (before the header named
the collected data) are still read: they carry every kind of data. This module must never
import pybullet.
"""

from __future__ import annotations

import json
import math
import os
import re
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any, BinaryIO, get_args

import numpy as np

from rei.catalogue import Box, Cylinder, Footprint, Polygon, Tile
from rei.generators.output import open_output
from rei.lang.mission.faults import fault_name_problem
from rei.lang.mission.model import COLLECTED_DATA, REQUIRED_DATA
from rei.lang.source import file_kind, repeated_key
from rei.runtime.errors import RunError
from rei.runtime.messages import (
    BELIEF_DATA,
    FAILURE_CAUSES,
    MISSION_EVENT_KINDS,
    OBJECT_ROLES,
    SCHEMA_VERSION,
    TASK_EVENT_KINDS,
    UNCOLLECTED,
    GoalFacts,
    LaserScan,
    MissionEvent,
    MissionFacts,
    NavState,
    ObservedObject,
    RobotBelief,
    Sample,
    StreamHeader,
)
from rei.runtime.results import Outcome

FORMAT = "rei-trace"
TRACE_VERSION = 1
OUTCOMES: tuple[str, ...] = get_args(Outcome)
NAV_STATES: tuple[str, ...] = tuple(s.value for s in NavState)
PREVIOUS_SCHEMA = 3
"""The sample schema before the header named the collected data: read as collecting all."""


class TraceError(RunError):
    """A trace file cannot be read (or written): wrong format or version, or damaged."""


def _dumps(value: Any) -> str:
    return json.dumps(value, separators=(",", ":"), allow_nan=False, ensure_ascii=False)


def _footprint_json(fp: Footprint) -> dict[str, Any]:
    if isinstance(fp, Box):
        return {"shape": "box", "size": [fp.size_x, fp.size_y]}
    if isinstance(fp, Cylinder):
        return {"shape": "cylinder", "radius": fp.radius}
    if isinstance(fp, Polygon):
        return {"shape": "polygon", "points": [list(p) for p in fp.points]}
    return {"shape": "tile"}


def _object_json(o: ObservedObject) -> dict[str, Any]:
    return {"name": o.name, "role": o.role, "type": o.type,
            "footprint": _footprint_json(o.footprint), "height": o.height}


def header_json(h: StreamHeader) -> dict[str, Any]:
    return {"format": FORMAT, "trace_version": TRACE_VERSION, "version": h.version,
            "world": h.world, "mission": h.mission, "seed": h.seed, "rate": h.rate,
            "robot": _object_json(h.robot), "objects": [_object_json(o) for o in h.objects],
            "tile_size": h.tile_size, "floors": [list(f) for f in h.floors],
            "laser_mount": list(h.laser_mount),
            "mission_facts": _facts_json(h.mission_facts) if h.mission_facts else None,
            "data": list(h.data),
            # only in a stream with faults: a run without keeps the bytes it always had
            **({"faults": [{"name": n, "entry": e} for n, e in h.faults]} if h.faults else {})}


def _facts_json(f: MissionFacts) -> dict[str, Any]:
    goals = [{"name": g.name, "x": g.x, "y": g.y, "heading": g.heading,
              "tolerance": g.tolerance, "heading_tolerance": g.heading_tolerance,
              "timeout": g.timeout} for g in f.goals]
    return {"goals": goals, "cycles": f.cycles, "time_limit": f.time_limit,
            "speed_limit": f.speed_limit, "turn_limit": f.turn_limit,
            "mission_max_speed": f.mission_max_speed}


def _event_json(e: MissionEvent) -> dict[str, Any]:
    return {"kind": e.kind, "time": e.time, "task": e.task, "index": e.index, "reason": e.reason,
            "cause": e.cause}


def _sample_json(sample: Sample, poses: list[list[Any]], twists: list[list[Any]],
                 data: tuple[str, ...] = COLLECTED_DATA) -> dict[str, Any]:
    """A sample's line, with only the ``data`` collected (the header's)."""
    b = sample.belief
    belief: dict[str, Any] = {}
    if "odometry" in data:
        belief.update(odom=list(b.odom), odom_twist=list(b.odom_twist))
    if "laser" in data:
        scan = None
        if b.scan is not None:
            s = b.scan
            scan = {"angle_min": s.angle_min, "angle_increment": s.angle_increment,
                    "range_min": s.range_min, "range_max": s.range_max,
                    "ranges": np.asarray(s.ranges, dtype=float).tolist()}
        belief.update(laser_min=b.laser_min, scan=scan)
    if "nav_state" in data:
        belief.update(nav_state=b.nav_state.value, task=b.task, cmd=list(b.cmd))
    line: dict[str, Any] = {
        "seq": sample.seq, "time": sample.time,
        "robot_pose": list(sample.robot_pose), "robot_twist": list(sample.robot_twist),
        "poses": poses, "twists": twists, "belief": belief,
    }
    if "mission_events" in data:
        line["events"] = [_event_json(e) for e in sample.events]
    line["contacts"] = list(sample.contacts)
    if sample.faults:
        line["faults"] = list(sample.faults)
    return line


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
_GOAL_KEYS = frozenset(("name", "x", "y", "heading", "tolerance", "heading_tolerance",
                        "timeout"))
_SAMPLE_KEYS = frozenset(("seq", "time", "robot_pose", "robot_twist", "poses", "twists",
                          "belief", "events", "contacts"))
"""A sample of a stream collecting everything; ``events`` only with mission_events."""
_SCAN_KEYS = frozenset(("angle_min", "angle_increment", "range_min", "range_max", "ranges"))
_EVENT_KEYS = frozenset(("kind", "time", "task", "index", "reason", "cause"))
_END_KEYS = frozenset(("end", "outcome", "reason"))
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


def _footprint(value: Any, where: str, field: str, robot: bool) -> Footprint:
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


def _object(value: Any, where: str, field: str, robot: bool = False) -> ObservedObject:
    o = _Fields(value, where, field, _OBJECT_KEYS, "an observed object (a JSON object)")
    return ObservedObject(o.text("name"), o.choice("role", OBJECT_ROLES),  # type: ignore[arg-type]
                          o.text("type"), _footprint(o.data["footprint"], where,
                                                     o.field("footprint"), robot),
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
    f = _Fields(value, where, "mission_facts", _FACTS_KEYS,
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
                        f.optional_number("mission_max_speed", **positive))


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
        h.number("rate", low=0.0, low_open=True), _object(data["robot"], where, "robot", True),
        tuple(_object(o, where, f"objects[{i}]") for i, o in enumerate(objects)),
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


def _end(data: Any, where: str, last_time: float | None) -> tuple[float, str, str]:
    """(end time, outcome, reason) of an end line after a sample at ``last_time``."""
    e = _Fields(data, where, "", _END_KEYS, "the end line")
    low, note = (0.0, "") if last_time is None else (last_time, "(the last sample's time)")
    return e.number("end", low=low, note=note), e.choice("outcome", OUTCOMES), e.text("reason")


class _StreamRules:
    """What holds between the lines of one trace: sequence numbers without gaps, times that
    never go back, mission events in order, rows within the header's object table."""

    def __init__(self, n_objects: int, data: tuple[str, ...] = COLLECTED_DATA,
                 faults: tuple[str, ...] = ()) -> None:
        self.n = n_objects
        self.data = data
        self.faults = faults
        """The header's fault names, in its order: a sample's active faults are among them."""
        self.belief_keys = frozenset(k for kind, keys in BELIEF_DATA.items() if kind in data
                                     for k in keys)
        self.with_events = "mission_events" in data
        self.sample_keys = _SAMPLE_KEYS if self.with_events else _SAMPLE_KEYS - {"events"}
        self.poses = np.zeros((n_objects, 3))
        self.twists = np.zeros((n_objects, 3))
        self.seq = 0
        """The next sample's sequence number."""
        self.time: float | None = None
        """The previous sample's time."""
        self.event_time = 0.0
        self.events = 0
        self.ended_at: float | None = None
        """When the mission's 'end' event happened; nothing may follow it."""

    def sample(self, data: Any, where: str) -> Sample:
        keyed = isinstance(data, dict) and "faults" in data and self.faults
        d = _Fields(data, where, "", self.sample_keys | {"faults"} if keyed
                    else self.sample_keys, "a sample line (a JSON object)")
        seq = data["seq"]
        if not (_is_whole(seq) and seq == self.seq):
            raise TraceError(f"{where}: seq: expected {self.seq} (samples are numbered 0, 1, "
                             f"2, ... without gaps), found {_show(seq)}")
        previous = self.time
        time = d.number("time", low=0.0 if previous is None else previous,
                        note="" if previous is None else "(the previous sample's time)")
        robot_pose = d.numbers("robot_pose", 3, "[x, y, yaw]")
        robot_twist = d.numbers("robot_twist", 3, "[vx, vy, wz]")
        first = previous is None
        self._rows(d, "poses", self.poses, first)
        self._rows(d, "twists", self.twists, first)
        belief = self._belief(d.fields("belief", self.belief_keys,
                                       "the robot's belief of the collected data (a JSON "
                                       "object)"))
        events = self._events(d, time, 0.0 if previous is None else previous) \
            if self.with_events else ()
        contacts = self._contacts(data["contacts"], where)
        faults = self._active(data["faults"], where) if keyed else ()
        self.seq, self.time = seq + 1, time
        return Sample(seq, time, robot_pose, robot_twist,  # type: ignore[arg-type]
                      self.poses.copy(), self.twists.copy(), belief, events, contacts, faults)

    def _active(self, value: Any, where: str) -> tuple[str, ...]:
        """A sample's active faults: some of the header's, in its order, each once (absent
        when none is active)."""
        if isinstance(value, list) and value and all(isinstance(n, str) for n in value):
            order = [self.faults.index(n) if n in self.faults else -1 for n in value]
            if -1 not in order and order == sorted(set(order)):
                return tuple(value)
        raise TraceError(f"{where}: faults: expected a non-empty list of the header's fault "
                         f"names ({', '.join(self.faults)}) in its order, each once, found "
                         f"{_show(value)}")

    def _rows(self, d: _Fields, key: str, target: np.ndarray, first: bool) -> None:
        """Rows [index, a, b, c] of the objects that changed, by increasing index; the first
        sample has every object's (an object never given would sit at the origin)."""
        rows = d.array(key, "[index, a, b, c] rows")
        n, last = self.n, -1
        for k, row in enumerate(rows):
            if not (isinstance(row, list) and len(row) == 4):
                raise TraceError(f"{d.where}: {key}[{k}]: expected a row [index, a, b, c], "
                                 f"found {_show(row)}")
            i = row[0]
            if not (_is_whole(i) and last < i < n):
                order = f" above the previous row's {last}" if last >= 0 else ""
                raise TraceError(f"{d.where}: {key}[{k}][0]: expected an index of the header's "
                                 f"{n} objects (0 to {n - 1}){order}, found {_show(i)}")
            if not (_is_number(row[1]) and _is_number(row[2]) and _is_number(row[3])):
                raise TraceError(f"{d.where}: {key}[{k}]: expected three finite numbers after "
                                 f"the index, found {_show(row)}")
            target[i] = row[1:]
            last = i
        if first and len(rows) != n:
            raise TraceError(f"{d.where}: {key}: expected a row for each of the header's {n} "
                             f"objects in the first sample, found {len(rows)}")

    def _belief(self, b: _Fields) -> RobotBelief:
        """The belief of the collected data; ``UNCOLLECTED``'s values for the rest."""
        u = UNCOLLECTED
        odom, odom_twist = u.odom, u.odom_twist
        laser_min, scan = u.laser_min, u.scan
        nav_state, task, cmd = u.nav_state, u.task, u.cmd
        if "odometry" in self.data:
            odom = b.numbers("odom", 3, "[x, y, yaw]")  # type: ignore[assignment]
            odom_twist = b.numbers("odom_twist", 2, "[linear, angular]")  # type: ignore[assignment]
        if "laser" in self.data:
            laser_min = b.number("laser_min", low=0.0)
            if b.data["scan"] is not None:
                scan = self._scan(b.fields("scan", _SCAN_KEYS, "a laser scan (a JSON object, "
                                                               "or null)"))
        if "nav_state" in self.data:
            nav_state = NavState(b.choice("nav_state", NAV_STATES))
            task = b.optional_text("task")
            cmd = b.numbers("cmd", 2, "[linear, angular]")  # type: ignore[assignment]
        return RobotBelief(odom, odom_twist, laser_min, scan, nav_state, task, cmd)

    @staticmethod
    def _scan(s: _Fields) -> LaserScan:
        angle_min = s.number("angle_min")
        increment = s.number("angle_increment", low=0.0, low_open=True)
        range_min = s.number("range_min", low=0.0)
        range_max = s.number("range_max", low=range_min, low_open=True, note="(range_min)")
        ranges = s.array("ranges", "ranges")
        field = s.field("ranges")
        if not ranges:
            raise TraceError(f"{s.where}: {field}: expected at least one range, found none")
        if not _FLOATS.issuperset(map(type, ranges)):  # 360 beams: one pass for the usual case
            for k, r in enumerate(ranges):
                _number(r, s.where, f"{field}[{k}]", low=0.0)
        values = np.array(ranges, dtype=float)
        if not (bool(np.isfinite(values).all()) and bool((values >= 0.0).all())):
            k = int(np.flatnonzero(~(np.isfinite(values) & (values >= 0.0)))[0])
            _number(ranges[k], s.where, f"{field}[{k}]", low=0.0)
        return LaserScan(angle_min, increment, range_min, range_max, values)

    def _events(self, d: _Fields, time: float, previous: float) -> tuple[MissionEvent, ...]:
        raw = d.array("events", "mission events")
        events = []
        for k, item in enumerate(raw):
            e = _Fields(item, d.where, f"events[{k}]", _EVENT_KEYS,
                        "a mission event (a JSON object)")
            kind = e.choice("kind", MISSION_EVENT_KINDS)
            if self.ended_at is not None:
                raise TraceError(f"{d.where}: events[{k}].kind: expected no event after the "
                                 f"mission's 'end' at t={_fmt(self.ended_at)}, found "
                                 f"{kind!r}")
            if kind == "begin" and self.events:
                raise TraceError(f"{d.where}: events[{k}].kind: expected 'begin' only as the "
                                 f"first event of the mission, found it after {self.events}")
            low = max(previous, self.event_time)
            at = e.number("time", low=low, high=time,
                          note="(after the previous event or sample, by this sample)")
            if kind in TASK_EVENT_KINDS:
                task, index = e.text("task"), e.whole("index", 0)
            else:
                for key in ("task", "index"):
                    if e.data[key] is not None:
                        raise TraceError(f"{d.where}: {e.field(key)}: expected null for kind "
                                         f"{kind!r}, found {_show(e.data[key])}")
                task, index = None, None
            reason = e.text("reason")
            allowed = FAILURE_CAUSES if kind == "task_fail" else ("",)
            cause = e.choice("cause", allowed, f" for kind {kind!r}")
            events.append(MissionEvent(kind, at, task, index, reason,  # type: ignore[arg-type]
                                       cause))
            self.event_time = at
            self.events += 1
            if kind == "end":
                self.ended_at = at
        return tuple(events)

    def _contacts(self, value: Any, where: str) -> tuple[int, ...]:
        """Indices of touched objects: a bad one would make the monitor see a collision with
        the wrong body, or none."""
        n = self.n
        if isinstance(value, list) and all(_is_whole(i) and 0 <= i < n for i in value) \
                and all(a < b for a, b in zip(value, value[1:], strict=False)):
            return tuple(value)
        raise TraceError(f"{where}: contacts: expected indices of the header's {n} objects "
                         f"(0 to {n - 1}) in increasing order, found {_show(value)}")

    def end(self, data: Any, where: str) -> tuple[float, str, str]:
        return _end(data, where, self.time)


# ---- writing --------------------------------------------------------------------------------


class TraceEncoder:
    """Headers, samples and end records into trace lines (JSON text without the newline),
    each checked by the reader's rules first: what ``TraceWriter`` writes to trace.jsonl and
    an MCAP recording carries on its /rei/trace channel (``rei.runtime.observation.recordings``).

    ``where`` names the output in errors (``where:LINE``). Raises ``TraceError`` for a record
    the reader would refuse; after one, the encoder is spent.
    """

    def __init__(self, where: str) -> None:
        self.where = where
        self._poses: np.ndarray | None = None
        self._twists: np.ndarray | None = None
        self._rules: _StreamRules | None = None
        self.line = 0
        """Lines encoded so far."""

    def header(self, header: StreamHeader) -> str:
        data = header_json(header)
        _header(data, f"{self.where}:1")
        self._rules = _StreamRules(len(header.objects), header.data,
                                   tuple(n for n, _ in header.faults))
        self.line = 1
        return _dumps(data)

    @staticmethod
    def _changed(new: np.ndarray, old: np.ndarray | None) -> list[list[Any]]:
        if old is None or old.shape != new.shape:
            rows: list[int] = list(range(len(new)))
        else:
            rows = np.nonzero((new != old).any(axis=1))[0].tolist()
        return [[i, *new[i].tolist()] for i in rows]

    def sample(self, sample: Sample) -> str:
        assert self._rules is not None, "header() first"
        line = _sample_json(sample, self._changed(sample.poses, self._poses),
                            self._changed(sample.twists, self._twists), self._rules.data)
        self._rules.sample(line, f"{self.where}:{self.line + 1}")
        self.line += 1
        # Only what was encoded is the base of the next sample's changed rows.
        self._poses, self._twists = sample.poses.copy(), sample.twists.copy()
        return _dumps(line)

    def end(self, end_time: float, outcome: str, reason: str) -> str:
        assert self._rules is not None, "header() first"
        line = {"end": end_time, "outcome": outcome, "reason": reason}
        self._rules.end(line, f"{self.where}:{self.line + 1}")
        self.line += 1
        return _dumps(line)


class TraceWriter:
    """A ``SampleSink`` writing the trace file; ``path`` appears only when finished.

    Raises ``TraceError`` (and writes nothing more) for a header, sample or end the reader
    would refuse: a non-finite number, a time going back, an unknown kind, ...
    ``line`` is the last line written (without its newline): a sink after this one can
    carry it as is (the MCAP recorder does) instead of encoding the record again.
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.partial = self.path.with_name(self.path.name + ".partial")
        self._file: IO[str] | None = None
        self._encoder = TraceEncoder(str(self.partial))
        self.line = ""

    def _refuse(self, exc: TraceError) -> TraceError:
        if self._file is not None:
            self._file.close()
            self._file = None
        return TraceError(f"cannot write the trace: {exc}")

    def start(self, header: StreamHeader) -> None:
        try:
            text = self._encoder.header(header)
        except TraceError as exc:
            raise self._refuse(exc) from None
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._file = open_output(self.partial)  # never written through a link
        self._file.write(text + "\n")
        self.line = text

    def feed(self, sample: Sample) -> None:
        assert self._file is not None, "start() first"
        try:
            text = self._encoder.sample(sample)
        except TraceError as exc:
            raise self._refuse(exc) from None
        self._file.write(text + "\n")
        self.line = text

    def finish(self, end_time: float, outcome: str, reason: str) -> None:
        if self._file is None:
            return
        try:
            text = self._encoder.end(end_time, outcome, reason)
        except TraceError as exc:
            raise self._refuse(exc) from None
        self._file.write(text + "\n")
        self.line = text
        self._file.flush()
        os.fsync(self._file.fileno())
        self._file.close()
        self._file = None
        os.replace(self.partial, self.path)


    def abandon(self) -> None:
        """Stop writing and remove the partial file (a stream that broke off: no trace)."""
        if self._file is not None:
            self._file.close()
            self._file = None
        self.partial.unlink(missing_ok=True)


def write(path: str | Path, header: StreamHeader, samples: Iterator[Sample] | list[Sample],
          end_time: float, outcome: str = "completed", reason: str = "") -> None:
    """Write a whole trace at once (what a run streams through ``TraceWriter``)."""
    writer = TraceWriter(path)
    writer.start(header)
    for sample in samples:
        writer.feed(sample)
    writer.finish(end_time, outcome, reason)


# ---- reading --------------------------------------------------------------------------------


def _load(raw: bytes, where: str) -> Any:
    """One line's JSON value; a line that is not JSON text is a located error."""
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise TraceError(f"{where}: expected UTF-8 text, found the bytes "
                         f"{raw[exc.start:exc.start + 8]!r} at column {exc.start + 1}") from None
    if not text.strip():
        raise TraceError(f"{where}: expected a JSON object, found an empty line")
    try:
        value = json.loads(text, object_pairs_hook=_unique_fields)
    except _RepeatedField as exc:
        raise TraceError(f"{where}: expected each field once, found {_show(exc.key)} "
                         f"{exc.count} times") from None
    except json.JSONDecodeError as exc:
        raise TraceError(f"{where}: expected a JSON object, found {_show(text.strip())} "
                         f"({exc.msg} at column {exc.colno})") from None
    except (ValueError, RecursionError) as exc:  # a 5000-digit number, [[[[... nested
        raise TraceError(f"{where}: expected a JSON object, found a line JSON cannot hold "
                         f"({type(exc).__name__}: {_show(str(exc))})") from None
    if _ESCAPED_SURROGATE.search(text):
        try:
            json.dumps(value, ensure_ascii=False).encode("utf-8")
        except UnicodeEncodeError:
            raise TraceError(f"{where}: expected text, found a lone surrogate escape "
                             f"(\\ud800-\\udfff without its pair), which no file or "
                             f"terminal can show") from None
    return value


class _RepeatedField(ValueError):
    def __init__(self, key: str, count: int) -> None:
        super().__init__(key)
        self.key, self.count = key, count


def _unique_fields(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """A JSON object's fields, each named once: with a repeated field JSON keeps the last
    value, so `"contacts": [1], "contacts": []` would hide a contact."""
    repeated = repeated_key(pairs)
    if repeated is not None:
        raise _RepeatedField(*repeated)
    return dict(pairs)


_ESCAPED_SURROGATE = re.compile(r"\\[uU][dD][89a-fA-F]")


def open_regular(path: Path) -> BinaryIO:
    """The trace opened for reading: a regular file only (a FIFO would block, /dev/zero never
    ends a line), checked before it is opened and again through the descriptor."""
    try:
        kind = file_kind(os.stat(path).st_mode)
        if kind is None:
            fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
            kind = file_kind(os.fstat(fd).st_mode)
            if kind is None:
                os.set_blocking(fd, True)
                return os.fdopen(fd, "rb")
            os.close(fd)
    except OSError as exc:
        raise TraceError(f"cannot read the trace '{path}': {exc.strerror or exc}") from None
    raise TraceError(f"cannot read the trace '{path}': expected a regular file, found {kind}")


def _is_partial(path: Path) -> bool:
    """A killed run's trace (``NAME.partial``) may lack its end line; a finished one may not."""
    return path.name.endswith(".partial")


def _no_end(path: Path, lineno: int) -> TraceError:
    return TraceError(f"{path}:{lineno}: expected the end line {{\"end\": time, \"outcome\": "
                      f"..., \"reason\": ...}} after the last sample, found the end of the file "
                      f"(the trace was cut short; a killed run leaves only NAME.partial)")


class TraceDecoder:
    """Trace lines back into records, checked by the rules the writer applies: the header
    first (``header``), then a sample or the end record per line (``line``). What
    ``read_trace`` reads a trace file with, and ``rei.runtime.observation.recordings`` an MCAP
    recording's /rei/trace channel. ``where`` in every call names the line in errors."""

    def __init__(self, first: bytes, where: str) -> None:
        data = _load(first, where)
        if not isinstance(data, dict):
            raise TraceError(f"{where}: expected a REI trace header (a JSON object), found "
                             f"{_show(data)}")
        self.header = _header(data, where)
        self._rules = _StreamRules(len(self.header.objects), self.header.data,
                                   tuple(n for n, _ in self.header.faults))

    def resume_at(self, seq: int, poses: np.ndarray, twists: np.ndarray) -> None:
        """Accept the sample numbered ``seq`` next, on top of every object's pose and twist
        at that sample (a keyframe): a reader that missed the samples before it (a monitor
        on a bus) goes on. Rows are changes, so after a gap only a keyframe makes the next
        line readable."""
        if poses.shape != self._rules.poses.shape or twists.shape != self._rules.twists.shape:
            raise TraceError(f"a keyframe of {len(self._rules.poses)} rows expected, found "
                             f"{len(poses)} and {len(twists)}")
        self._rules.seq = seq
        self._rules.poses[:], self._rules.twists[:] = poses, twists
        if self._rules.time is None:  # not the first sample of the stream: rows are changes
            self._rules.time = 0.0

    def line(self, raw: bytes, where: str) -> Sample | tuple[float, str, str]:
        """The sample of a line, or (end time, outcome, reason) of the end line."""
        data = _load(raw, where)
        try:
            if isinstance(data, dict) and "end" in data:
                return self._rules.end(data, where)
            return self._rules.sample(data, where)
        except (KeyError, IndexError, TypeError, ValueError, OverflowError) as exc:
            # the rules name every field they refuse; this is a last line of defence
            raise TraceError(f"{where}: damaged line ({type(exc).__name__}: {exc})") from None


def _samples(handle: BinaryIO, decoder: TraceDecoder, path: Path) -> Iterator[Sample]:
    lineno = 1
    with handle:
        lines = enumerate(handle, start=2)
        for lineno, raw in lines:
            record = decoder.line(raw, f"{path}:{lineno}")
            if not isinstance(record, Sample):
                for later, _ in lines:
                    raise TraceError(f"{path}:{later}: expected nothing after the end "
                                     f"line (line {lineno}), found another line")
                return
            yield record
    if not _is_partial(path):
        raise _no_end(path, lineno + 1)


def read_trace(path: str | Path) -> tuple[StreamHeader, Iterator[Sample]]:
    """The header and a lazy iterator over the samples of a trace (or its .partial file).

    ``TraceError`` for a damaged header here, for a damaged line when the iterator reaches it
    (also a finished trace without its end line, or anything after it)."""
    path = Path(path)
    handle = open_regular(path)
    try:
        decoder = TraceDecoder(handle.readline(), f"{path}:1")
    except BaseException:
        handle.close()
        raise
    return decoder.header, _samples(handle, decoder, path)


def read_trace_end(path: str | Path) -> tuple[float, str, str] | None:
    """(end time, outcome, reason) of the trace's end line, checked as ``read_trace`` checks
    it: the only end line, the last line, no earlier than the last sample. None for a
    ``.partial`` file without one; ``TraceError`` for a finished trace without one."""
    path = Path(path)
    end: tuple[int, Any] | None = None
    last: tuple[int, Any] | None = None
    lineno = 1
    with open_regular(path) as handle:
        handle.readline()
        for lineno, raw in enumerate(handle, start=2):
            if end is not None:
                raise TraceError(f"{path}:{lineno}: expected nothing after the end line (line "
                                 f"{end[0]}), found another line")
            if raw.startswith(b'{"seq":'):  # a sample as the writer writes it: parsed if last
                last = (lineno, raw)
                continue
            data = _load(raw, f"{path}:{lineno}")
            if isinstance(data, dict) and "end" in data:
                end = (lineno, data)
            else:
                last = (lineno, data)
    if end is None:
        if _is_partial(path):
            return None
        raise _no_end(path, lineno + 1)
    last_time = None
    if last is not None:
        where = f"{path}:{last[0]}"
        data = _load(last[1], where) if isinstance(last[1], bytes) else last[1]
        time = data.get("time") if isinstance(data, dict) else None
        last_time = _number(time, where, "time", low=0.0)
    return _end(end[1], f"{path}:{end[0]}", last_time)
