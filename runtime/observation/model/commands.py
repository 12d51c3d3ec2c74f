"""How hard the robot's commands change: the accelerations the command stream asks of the base.

The samples carry the last command the controller sent (``RobotBelief.cmd``), not when it
was sent: a controller commands at its own rate (10 Hz in REI's runs, irregular in a replayed
/cmd_vel), the samples come at theirs. So a command *tick* is seen as a sample whose command
differs from the previous sample's, and a change is divided by the time it can have taken:

- at least the interval between the sample that showed the old command and the one that shows
  the new (the change happened within it; never ~0, as samples are ordered and
  ``MIN_INTERVAL`` bounds it), and
- at most the interval since the previous change was seen, capped by the shortest interval
  between two changes seen so far (the controller's period, or more): a command held for 5 s
  and then dropped to zero was dropped within one period, not over 5 s.

Before two changes were seen the period is not known and the time since the previous change
stands: the first step from rest is judged mildly rather than wrongly. Each figure is that of
the step into the current command, kept until the command changes again. Speeding up (the
same sign, at least the last magnitude) is an acceleration, anything else a deceleration, as
Nav2's velocity smoother decides it. This module must never import the simulation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

MIN_INTERVAL = 1e-3
"""Seconds: no command change is divided by less (two samples with nearly one stamp)."""


@dataclass(frozen=True)
class CommandRates:
    """The step into the current command (0 where it was not of that kind)."""

    accel: float = 0.0
    """m/s^2 the linear command sped up by."""
    decel: float = 0.0
    """m/s^2 the linear command slowed down (or reversed) by."""
    turn_accel: float = 0.0
    turn_decel: float = 0.0
    """rad/s^2, likewise for the angular command."""


NO_CHANGE = CommandRates()


def _split(last: float, new: float, rate: float) -> tuple[float, float]:
    """(acceleration, deceleration) of a change from ``last`` to ``new`` at ``rate``."""
    if last * new >= 0.0 and abs(new) >= abs(last):
        return rate, 0.0
    return 0.0, rate


class CommandTracker:
    """Watches the command of every accepted sample; ``observe`` gives the current rates."""

    def __init__(self) -> None:
        self.command: tuple[float, float] | None = None
        self.sample_time: float | None = None
        """Of the last sample seen."""
        self.changed_at: float | None = None
        """When the current command was first seen."""
        self.changed = False
        """Whether the current command is a change (not the run's first command): only the
        interval between two changes tells the period."""
        self.period = math.inf
        """The shortest interval between two changes seen so far."""
        self.rates = NO_CHANGE

    def observe(self, time: float, command: tuple[float, float]) -> CommandRates:
        last, previous_sample = self.command, self.sample_time
        self.sample_time = time
        if last is None or previous_sample is None:
            self.command, self.changed_at = command, time
            return self.rates
        if command == last:
            return self.rates
        since = time - self.changed_at if self.changed_at is not None else math.inf
        if self.changed and since > MIN_INTERVAL:
            self.period = min(self.period, since)
        within = max(time - previous_sample, MIN_INTERVAL)
        interval = max(within, min(since, self.period))
        lin_accel, lin_decel = _split(last[0], command[0], abs(command[0] - last[0]) / interval)
        ang_accel, ang_decel = _split(last[1], command[1], abs(command[1] - last[1]) / interval)
        self.command, self.changed_at, self.changed = command, time, True
        self.rates = CommandRates(lin_accel, lin_decel, ang_accel, ang_decel)
        return self.rates
