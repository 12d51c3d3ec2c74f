"""Typed, immutable model of a mission: the room it runs in and its goals."""

from __future__ import annotations

from dataclasses import dataclass

from rei.lang.errors import Span
from rei.lang.mission.faults import FaultDefinition
from rei.lang.room.model import NameRef

DEFAULT_TOLERANCE = 0.25
"""Metres; the ROS navigation stack's usual xy goal tolerance."""
DEFAULT_TIMEOUT = 120.0
"""Seconds per goal."""
DEFAULT_HEADING_TOLERANCE = 15.0
"""Degrees; how far the final heading may be off a goal's heading (ignored without one)."""
DEFAULT_SAMPLE_RATE = 10.0
DEFAULT_SETTLE = 3.0
"""Seconds a mission goes on after its last task ended (``settle``): a navigator that never
stops, or drifts off after reporting success, is seen doing it."""
"""Samples per second of simulation time: twice the default laser rate, so no scan is lost."""
MAX_SAMPLE_RATE = 1000.0
"""Samples per second at most (the run's physics rate, default 100, must be a multiple)."""
COLLECTED_DATA = ("ground_truth", "odometry", "laser", "nav_state", "mission_events")
"""What the data collector can forward, in the order monitor.json and the trace list them:
the bodies' ground truth (poses, velocities, contacts: always collected), the robot's
odometry, its laser scans, its navigation state (with the task and the velocity command),
and the mission executor's events. A mission collects all of them unless its ``monitor``
block names a subset."""
REQUIRED_DATA = ("ground_truth",)
"""Data every collection includes: each sample is built around the bodies' poses."""


@dataclass(frozen=True)
class Goal:
    name: str
    floor: NameRef
    tolerance: float
    heading_deg: float | None
    timeout: float
    span: Span
    heading_tolerance_deg: float = DEFAULT_HEADING_TOLERANCE
    offset: tuple[float, float] = (0.0, 0.0)
    """Metres (x, y) from the floor's centre (``offset DX DY``)."""


@dataclass(frozen=True)
class Mission:
    name: str
    path: str
    span: Span
    room_path: str
    room_span: Span
    cycles: int
    time_limit: float | None
    max_speed: float | None
    goals: tuple[Goal, ...]
    sample_rate: float = DEFAULT_SAMPLE_RATE
    """Samples per second the data collector takes (the ``monitor`` block's ``rate``)."""
    data: tuple[str, ...] = COLLECTED_DATA
    """What the data collector forwards, a subset of COLLECTED_DATA in its order."""
    faults: tuple[FaultDefinition, ...] = ()
    """The ``fault`` section: what is injected between the sensors and the robot under test."""
    settle: float = DEFAULT_SETTLE
    """Seconds the mission goes on after its last task ended (``settle``)."""

    def task_sequence(self) -> tuple[Goal, ...]:
        """The goals in the order they are sent: the sequence repeated ``cycles`` times."""
        return self.goals * self.cycles

    def effective_time_limit(self) -> float:
        """The mission's time limit: as written, or the sum of the tasks' timeouts and the
        settle period."""
        if self.time_limit is not None:
            return self.time_limit
        return sum(g.timeout for g in self.task_sequence()) + self.settle
