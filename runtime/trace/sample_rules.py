"""The rules between the lines of one trace (``_StreamRules``): each sample line checked
against the header and the lines before it (sequence numbers, times, object rows, the
belief of the collected data, mission events, contacts, active faults), and the end line
(``_end``). Built on ``rules``' field checks. This module only checks: it never encodes,
opens or writes a file, must never import ``encode`` or ``read``, nor the simulation or
pybullet.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rei.lang.mission.model import COLLECTED_DATA
from rei.runtime.messages import (
    BELIEF_DATA,
    FAILURE_CAUSES,
    MISSION_EVENT_KINDS,
    TASK_EVENT_KINDS,
    UNCOLLECTED,
    LaserScan,
    MissionEvent,
    NavState,
    RobotBelief,
    Sample,
)
from rei.runtime.trace.format import NAV_STATES, OUTCOMES, TraceError
from rei.runtime.trace.rules import (
    _FLOATS,
    _Fields,
    _fmt,
    _is_number,
    _is_whole,
    _number,
    _show,
)

_SAMPLE_KEYS = frozenset(("seq", "time", "robot_pose", "robot_twist", "poses", "twists",
                          "belief", "events", "contacts"))
"""A sample of a stream collecting everything; ``events`` only with mission_events."""
_SCAN_KEYS = frozenset(("angle_min", "angle_increment", "range_min", "range_max", "ranges"))
_EVENT_KEYS = frozenset(("kind", "time", "task", "index", "reason", "cause"))
_END_KEYS = frozenset(("end", "outcome", "reason"))


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
