"""The data collector: samples the run at the monitor configuration's rate (thesis 5.1.4, 9.1).

It turns the simulator's ground truth and the robot's belief into typed ``Sample``s and
publishes them, in order, to every attached ``SampleSink``. Only the data the header names
(the mission's ``monitor`` block, thesis 6.1.2) are forwarded: the others carry the
``UNCOLLECTED`` values and no events (``rei.runtime.messages.BELIEF_DATA``). Mission events
and the robot's physical contacts (reported every physics step) are buffered and delivered
with the next sample, so none is lost between samples. This module must never import
pybullet or change the run: it only observes.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np

from rei.runtime.messages import (
    LaserScan,
    MissionEvent,
    NavState,
    RobotBelief,
    Sample,
    StreamHeader,
    collected_belief,
)
from rei.runtime.messages.sink import SampleSink


class DataCollector:
    def __init__(self, header: StreamHeader, sinks: Sequence[SampleSink],
                 laser_max_range: float) -> None:
        self.header = header
        self.laser_max_range = laser_max_range
        self.sinks = list(sinks)
        self.seq = 0
        self.last_time: float | None = None
        self._events: list[MissionEvent] = []
        self._contacts: set[int] = set()
        self._last_scan_time: float | None = None
        self.started = False
        self._laser = "laser" in header.data
        self._events_collected = "mission_events" in header.data

    def start(self) -> None:
        for sink in self.sinks:
            sink.start(self.header)
        self.started = True

    def event(self, events: Sequence[MissionEvent]) -> None:
        if self._events_collected:
            self._events.extend(events)

    def touch(self, indices: Iterable[int]) -> None:
        """Bodies (indices into the header's objects) the robot touches at this physics step;
        the next sample carries every body touched since the previous one."""
        self._contacts.update(indices)

    @property
    def has_pending_events(self) -> bool:
        return bool(self._events)

    def sample(self, time: float, robot_pose: tuple[float, float, float],
               robot_twist: tuple[float, float, float], poses: np.ndarray, twists: np.ndarray,
               odom: tuple[float, float, float], odom_twist: tuple[float, float],
               scan: LaserScan | None, scan_time: float | None, nav_state: NavState,
               task: str | None, cmd: tuple[float, float] = (0.0, 0.0),
               faults: tuple[str, ...] = ()) -> Sample:
        if not self._laser:
            scan = None
        fresh = scan if scan is not None and scan_time != self._last_scan_time else None
        self._last_scan_time = scan_time
        laser_min = float(scan.ranges.min()) if scan is not None else self.laser_max_range
        belief = collected_belief(RobotBelief(odom, odom_twist, laser_min, fresh, nav_state,
                                              task, cmd), self.header.data)
        sample = Sample(self.seq, time, robot_pose, robot_twist, poses, twists, belief,
                        tuple(self._events), tuple(sorted(self._contacts)), faults)
        self._events = []
        self._contacts = set()
        self.seq += 1
        self.last_time = time
        for sink in self.sinks:
            sink.feed(sample)
        return sample

    def finish(self, end_time: float, outcome: str, reason: str) -> None:
        if not self.started:
            return
        for sink in self.sinks:
            sink.finish(end_time, outcome, reason)
