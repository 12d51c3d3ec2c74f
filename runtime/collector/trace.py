"""The run's sample trace on disk: exact, deterministic JSON lines, and reading it back.

Line 1 is the stream header, then one line per sample, then an ``end`` line with the
outcome. Floats are written by ``repr`` (Python's shortest round-tripping form), so reading
a trace gives back bit-identical numbers. Per-object poses and twists are written as the
rows that changed since the previous sample (static objects appear once), which keeps a
trace of a room of walls small without losing exactness. The writer streams to
``NAME.partial`` and renames it into place at ``finish``: a trace file that exists is
complete; a killed run leaves only the partial file. This module must never import pybullet.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

import numpy as np

from rei.catalogue import Box, Cylinder, Footprint, Polygon, Tile
from rei.generators.output import open_output
from rei.runtime.errors import RunError
from rei.runtime.messages import (
    FAILURE_CAUSES,
    SCHEMA_VERSION,
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

FORMAT = "rei-trace"
TRACE_VERSION = 1


class TraceError(RunError):
    """A trace file cannot be read: wrong format or version, or damaged."""


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


def _footprint(data: dict[str, Any]) -> Footprint:
    shape = data["shape"]
    if shape == "box":
        return Box(data["size"][0], data["size"][1])
    if shape == "cylinder":
        return Cylinder(data["radius"])
    if shape == "polygon":
        return Polygon(tuple(tuple(p) for p in data["points"]))
    return Tile()


def _object_json(o: ObservedObject) -> dict[str, Any]:
    return {"name": o.name, "role": o.role, "type": o.type,
            "footprint": _footprint_json(o.footprint), "height": o.height}


def _object(d: dict[str, Any]) -> ObservedObject:
    return ObservedObject(d["name"], d["role"], d["type"], _footprint(d["footprint"]), d["height"])


def header_json(h: StreamHeader) -> dict[str, Any]:
    return {"format": FORMAT, "trace_version": TRACE_VERSION, "version": h.version,
            "world": h.world, "mission": h.mission, "seed": h.seed, "rate": h.rate,
            "robot": _object_json(h.robot), "objects": [_object_json(o) for o in h.objects],
            "tile_size": h.tile_size, "floors": [list(f) for f in h.floors],
            "laser_mount": list(h.laser_mount),
            "mission_facts": _facts_json(h.mission_facts) if h.mission_facts else None}


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


class TraceWriter:
    """A ``SampleSink`` writing the trace file; ``path`` appears only when finished."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.partial = self.path.with_name(self.path.name + ".partial")
        self._file: IO[str] | None = None
        self._poses: np.ndarray | None = None
        self._twists: np.ndarray | None = None

    def start(self, header: StreamHeader) -> None:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._file = open_output(self.partial)  # never written through a link
        self._file.write(_dumps(header_json(header)) + "\n")

    @staticmethod
    def _changed(new: np.ndarray, old: np.ndarray | None) -> list[list[Any]]:
        if old is None or old.shape != new.shape:
            rows: list[int] = list(range(len(new)))
        else:
            rows = np.nonzero((new != old).any(axis=1))[0].tolist()
        return [[i, *new[i].tolist()] for i in rows]

    def feed(self, sample: Sample) -> None:
        assert self._file is not None, "start() first"
        b = sample.belief
        scan = None
        if b.scan is not None:
            s = b.scan
            scan = {"angle_min": s.angle_min, "angle_increment": s.angle_increment,
                    "range_min": s.range_min, "range_max": s.range_max,
                    "ranges": np.asarray(s.ranges, dtype=float).tolist()}
        line = {
            "seq": sample.seq, "time": sample.time,
            "robot_pose": list(sample.robot_pose), "robot_twist": list(sample.robot_twist),
            "poses": self._changed(sample.poses, self._poses),
            "twists": self._changed(sample.twists, self._twists),
            "belief": {"odom": list(b.odom), "odom_twist": list(b.odom_twist),
                       "laser_min": b.laser_min, "scan": scan, "nav_state": b.nav_state.value,
                       "task": b.task, "cmd": list(b.cmd)},
            "events": [_event_json(e) for e in sample.events],
            "contacts": list(sample.contacts),
        }
        self._file.write(_dumps(line) + "\n")
        # Only what was written is the base of the next sample's changed rows.
        self._poses, self._twists = sample.poses.copy(), sample.twists.copy()

    def finish(self, end_time: float, outcome: str, reason: str) -> None:
        if self._file is None:
            return
        self._file.write(_dumps({"end": end_time, "outcome": outcome, "reason": reason}) + "\n")
        self._file.flush()
        os.fsync(self._file.fileno())
        self._file.close()
        self._file = None
        os.replace(self.partial, self.path)


def write(path: str | Path, header: StreamHeader, samples: Iterator[Sample] | list[Sample],
          end_time: float, outcome: str = "completed", reason: str = "") -> None:
    """Write a whole trace at once (what a run streams through ``TraceWriter``)."""
    writer = TraceWriter(path)
    writer.start(header)
    for sample in samples:
        writer.feed(sample)
    writer.finish(end_time, outcome, reason)


def _header(data: dict[str, Any], path: Path) -> StreamHeader:
    if data.get("format") != FORMAT:
        raise TraceError(f"{path}: expected a REI trace (format '{FORMAT}'), found "
                         f"{data.get('format')!r}")
    if data.get("trace_version") != TRACE_VERSION or data.get("version") != SCHEMA_VERSION:
        raise TraceError(f"{path}: expected trace version {TRACE_VERSION} with sample schema "
                         f"{SCHEMA_VERSION}, found {data.get('trace_version')!r} with schema "
                         f"{data.get('version')!r} (record it again with this REI)")
    return StreamHeader(data["version"], data["world"], data["mission"], data["seed"],
                        data["rate"], _object(data["robot"]),
                        tuple(_object(o) for o in data["objects"]), data["tile_size"],
                        tuple((f[0], f[1], f[2]) for f in data["floors"]),
                        _pair(data["laser_mount"], path, "laser_mount"),
                        _mission_facts(data["mission_facts"], f"{path}:1: mission_facts"))


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) \
        and math.isfinite(value)


def _pair(value: Any, path: Path, what: str, line: int = 1,
          form: str = "[x, y]") -> tuple[float, float]:
    """Two finite numbers (the edge rejects what the monitor cannot use)."""
    if not (isinstance(value, list) and len(value) == 2 and all(map(_is_number, value))):
        raise TraceError(f"{path}:{line}: {what}: expected two finite numbers {form}, found "
                         f"{value!r}")
    return float(value[0]), float(value[1])


def _number(data: dict[str, Any], key: str, where: str, *, low: float = -math.inf,
            high: float = math.inf, low_open: bool = False) -> float:
    """A finite number of the mission facts in its range; ``where`` locates the object."""
    value = data[key]
    if _is_number(value) and (value > low if low_open else value >= low) and value <= high:
        return float(value)
    bounds = []
    if math.isfinite(low):
        bounds.append(f"{'>' if low_open else '>='} {low:g}")
    if math.isfinite(high):
        bounds.append(f"<= {high:g}")
    expected = " ".join(("a finite number", " and ".join(bounds))).strip()
    raise TraceError(f"{where}.{key}: expected {expected}, found {value!r}")


def _optional(data: dict[str, Any], key: str, where: str, **bounds: Any) -> float | None:
    return None if data[key] is None else _number(data, key, where, **bounds)


def _mission_facts(data: Any, where: str) -> MissionFacts | None:
    """The header's mission facts, every number checked: a requirement reading a NaN goal or
    a zero speed limit would give verdicts about nothing."""
    if data is None:
        return None
    if not isinstance(data, dict) or not isinstance(data.get("goals"), list):
        raise TraceError(f"{where}: expected an object with a list of goals, found {data!r}")
    goals = []
    for i, g in enumerate(data["goals"]):
        at = f"{where}.goals[{i}]"
        if not isinstance(g, dict) or not isinstance(g.get("name"), str):
            raise TraceError(f"{at}: expected a goal with a name, found {g!r}")
        goals.append(GoalFacts(
            g["name"], _number(g, "x", at), _number(g, "y", at),
            _optional(g, "heading", at, low=-math.pi, high=math.pi),
            _number(g, "tolerance", at, low=0.0, low_open=True),
            _number(g, "heading_tolerance", at, low=0.0, low_open=True, high=math.pi),
            _number(g, "timeout", at, low=0.0, low_open=True)))
    if not goals:
        raise TraceError(f"{where}.goals: expected at least one goal, found none")
    cycles = data["cycles"]
    if not (isinstance(cycles, int) and not isinstance(cycles, bool) and cycles >= 1):
        raise TraceError(f"{where}.cycles: expected a whole number >= 1, found {cycles!r}")
    positive: dict[str, Any] = {"low": 0.0, "low_open": True}
    return MissionFacts(tuple(goals), cycles, _number(data, "time_limit", where, **positive),
                        _number(data, "speed_limit", where, **positive),
                        _number(data, "turn_limit", where, **positive),
                        _optional(data, "mission_max_speed", where, **positive))


def _event(e: dict[str, Any], path: Path, lineno: int) -> MissionEvent:
    cause = e["cause"]
    allowed = FAILURE_CAUSES if e["kind"] == "task_fail" else ("",)
    if cause not in allowed:
        raise TraceError(f"{path}:{lineno}: events: a '{e['kind']}' event's cause expected one "
                         f"of {', '.join(map(repr, allowed))}, found {cause!r}")
    return MissionEvent(e["kind"], e["time"], e["task"], e["index"], e["reason"], cause)


def _contacts(value: Any, n: int, path: Path, lineno: int) -> tuple[int, ...]:
    """Indices of touched objects: a bad one would make the monitor see a collision with the
    wrong body, or none."""
    if not isinstance(value, list) or not all(
            isinstance(i, int) and not isinstance(i, bool) and 0 <= i < n for i in value):
        raise TraceError(f"{path}:{lineno}: contacts: expected indices of the header's "
                         f"{n} objects (0 to {n - 1}), found {value!r}")
    return tuple(value)


def _samples(lines: Iterator[tuple[int, str]], n: int, path: Path) -> Iterator[Sample]:
    poses = np.zeros((n, 3))
    twists = np.zeros((n, 3))
    for lineno, text in lines:
        try:
            d = json.loads(text)
            if "end" in d:
                return
            for row in d["poses"]:
                poses[row[0]] = row[1:]
            for row in d["twists"]:
                twists[row[0]] = row[1:]
            b = d["belief"]
            scan = None
            if b["scan"] is not None:
                s = b["scan"]
                scan = LaserScan(s["angle_min"], s["angle_increment"], s["range_min"],
                                 s["range_max"], np.array(s["ranges"], dtype=float))
            cmd = _pair(b["cmd"], path, "belief.cmd", lineno, "[linear, angular]")
            belief = RobotBelief(tuple(b["odom"]), tuple(b["odom_twist"]),
                                 b["laser_min"], scan, NavState(b["nav_state"]), b["task"], cmd)
            events = tuple(_event(e, path, lineno) for e in d["events"])
            yield Sample(d["seq"], d["time"], tuple(d["robot_pose"]),
                         tuple(d["robot_twist"]), poses.copy(), twists.copy(),
                         belief, events, _contacts(d["contacts"], n, path, lineno))
        except (KeyError, IndexError, TypeError, ValueError) as exc:
            raise TraceError(f"{path}:{lineno}: damaged sample line ({exc})") from None


def read_trace(path: str | Path) -> tuple[StreamHeader, Iterator[Sample]]:
    """The header and a lazy iterator over the samples of a trace (or its .partial file)."""
    path = Path(path)
    try:
        handle = open(path, encoding="utf-8")  # noqa: SIM115  (closed by the generator)
    except OSError as exc:
        raise TraceError(f"cannot read the trace '{path}': {exc.strerror}") from None
    try:
        first = handle.readline()
        try:
            header = _header(json.loads(first), path)
        except json.JSONDecodeError:
            raise TraceError(f"{path}:1: expected a REI trace header (JSON), found "
                             f"{first[:40]!r}") from None
        except (KeyError, TypeError, IndexError) as exc:
            raise TraceError(f"{path}:1: damaged trace header ({exc})") from None
    except BaseException:
        handle.close()
        raise

    def lines() -> Iterator[tuple[int, str]]:
        with handle:
            for lineno, text in enumerate(handle, start=2):
                if text.strip():
                    yield lineno, text

    return header, _samples(lines(), len(header.objects), path)


def read_trace_end(path: str | Path) -> tuple[float, str, str] | None:
    """(end time, outcome, reason) from the trace's last line; None if it has none."""
    last = None
    with open(path, encoding="utf-8") as handle:
        for text in handle:
            if text.startswith('{"end"'):
                last = json.loads(text)
    return (last["end"], last["outcome"], last["reason"]) if last else None
