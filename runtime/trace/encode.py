"""Records into the trace's exact JSON lines, and writing them: ``header_json`` and the
encoding of samples, ``TraceEncoder`` (every line checked by the reader's rules before it
is given out), ``TraceWriter`` (streams to NAME.partial, renamed into place at ``finish``)
and ``write``. This module never reads a trace back (that is ``read``), and must never
import the simulation or pybullet.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

import numpy as np

from rei.catalogue.codec import footprint_json
from rei.generators.output import open_output
from rei.lang.mission.model import COLLECTED_DATA
from rei.runtime.messages import MissionEvent, MissionFacts, ObservedObject, Sample, StreamHeader
from rei.runtime.trace.format import FORMAT, TRACE_VERSION, TraceError
from rei.runtime.trace.rules import COMMAND_LIMITS, _header
from rei.runtime.trace.sample_rules import _StreamRules


def _dumps(value: Any) -> str:
    return json.dumps(value, separators=(",", ":"), allow_nan=False, ensure_ascii=False)


def _object_json(o: ObservedObject) -> dict[str, Any]:
    return {"name": o.name, "role": o.role, "type": o.type,
            "footprint": footprint_json(o.footprint), "height": o.height}


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
            "mission_max_speed": f.mission_max_speed,
            # only when known: a header without them reads as before (JSON has no inf)
            **({key: getattr(f, key) for key in COMMAND_LIMITS}
               if all(math.isfinite(getattr(f, key)) for key in COMMAND_LIMITS) else {})}


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
