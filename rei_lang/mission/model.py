"""Typed, immutable model of a mission: the room it runs in and its goals."""

from __future__ import annotations

from dataclasses import dataclass

from rei.lang.errors import Span
from rei.lang.room.model import NameRef

DEFAULT_TOLERANCE = 0.25
"""Metres; the ROS navigation stack's usual xy goal tolerance."""
DEFAULT_TIMEOUT = 120.0
"""Seconds per goal."""
DEFAULT_HEADING_TOLERANCE = 15.0
"""Degrees; how far the final heading may be off a goal's heading (ignored without one)."""


@dataclass(frozen=True)
class Goal:
    name: str
    floor: NameRef
    tolerance: float
    heading_deg: float | None
    timeout: float
    span: Span
    heading_tolerance_deg: float = DEFAULT_HEADING_TOLERANCE


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

    def task_sequence(self) -> tuple[Goal, ...]:
        """The goals in the order they are sent: the sequence repeated ``cycles`` times."""
        return self.goals * self.cycles

    def effective_time_limit(self) -> float:
        """The mission's time limit: as written, or the sum of the tasks' timeouts."""
        if self.time_limit is not None:
            return self.time_limit
        return sum(g.timeout for g in self.task_sequence())
