"""The contract between the run loop and the fault stage (issue 17).

The loop calls the stage at every control tick, in this order: ``scan`` (the latest measured
scan and when it was measured: what does the robot see now?), ``odometry`` (what does odometry
report now?), then, after the robot under test answered, ``command`` (what reaches the
motors?). ``signal`` is called when a ``.vepl`` signal fires (the monitor runs at the sample
rate, so a signal fired at a sample acts from the next control tick on); event-triggered faults
start or stop on it. A stage is per run: it is built with the run's seed and draws from its own
random stream, so a run without faults and a run with them share every other draw.

What the stage returns is what the robot under test receives and what the collector records
as the robot's belief (scan, odometry); the ground truth (poses, velocities, contacts) never
passes through it. ``timeline`` says which fault was active when, for the summary, events.csv
and the report; every sample names the faults active when it was taken (``active_at``).
This module must never import pybullet.
"""

from __future__ import annotations

from typing import Any, Protocol

from rei.runtime.messages import LaserScan

Pose = tuple[float, float, float]
Twist = tuple[float, float]
Command = tuple[float, float]


class FaultStage(Protocol):
    def scan(self, time: float, measured: LaserScan | None,
             measured_at: float | None) -> tuple[LaserScan | None, float | None]:
        """The scan the robot sees at ``time`` and its stamp, given the latest measured one
        (None before the first). Called every control tick with the same object until a new
        scan is measured: a stage that changes a scan does so once per measured scan and
        returns the same object on later calls."""
        ...

    def odometry(self, time: float, pose: Pose, twist: Twist) -> tuple[Pose, Twist]:
        """What odometry reports at ``time``, given what the odometry sensor measured."""
        ...

    def command(self, time: float, command: Command) -> Command:
        """What reaches the motors at ``time``, given what the robot under test asked for
        (before the drive limits clip it)."""
        ...

    def signal(self, time: float, name: str) -> None:
        """The ``.vepl`` signal ``name`` fired at simulation ``time``."""
        ...

    def timeline(self) -> tuple[tuple[str, float, float | None], ...]:
        """(fault, start, end) of every interval a fault was active, in start order; end
        None while it still is."""
        ...

    def described(self) -> tuple[tuple[str, str], ...]:
        """(name, entry as written in a fault section) of every fault the stage holds, in
        declaration order: the stream header carries them, so a replay knows the set-up."""
        ...


class NoFaults:
    """The empty stage: the robot receives exactly what the sensors measured."""

    def scan(self, time: float, measured: LaserScan | None,
             measured_at: float | None) -> tuple[LaserScan | None, float | None]:
        return measured, measured_at

    def odometry(self, time: float, pose: Pose, twist: Twist) -> tuple[Pose, Twist]:
        return pose, twist

    def command(self, time: float, command: Command) -> Command:
        return command

    def signal(self, time: float, name: str) -> None:
        return None

    def timeline(self) -> tuple[tuple[str, float, float | None], ...]:
        return ()

    def described(self) -> tuple[tuple[str, str], ...]:
        return ()


def active_at(timeline: tuple[tuple[str, float, float | None], ...], time: float,
              order: tuple[str, ...]) -> tuple[str, ...]:
    """The faults of ``timeline`` active at ``time`` (started, not yet ended), in ``order``
    (the declaration order): what a sample says was active when it was taken."""
    on = {name for name, start, end in timeline if start <= time and (end is None or time < end)}
    return tuple(name for name in order if name in on)


NO_FAULTS: FaultStage = NoFaults()


def fault_measurements(described: tuple[tuple[str, str], ...],
                       timeline: tuple[tuple[str, float, float | None], ...]
                       ) -> dict[str, Any]:
    """The summary's ``faults_injected`` (name, entry) and ``faults`` (the timeline) of a run,
    live or replayed; empty without faults, so such a run keeps the summary it always had."""
    if not described:
        return {}
    return {"faults_injected": [{"fault": name, "entry": entry} for name, entry in described],
            "faults": [{"fault": name, "start": start, "end": end}
                       for name, start, end in timeline]}


class SampledTimeline:
    """The faults' timeline as a stream's samples saw it (``rei replay``: the live stage is
    gone, its samples remain): an interval starts at the first sample naming a fault and ends
    at the first sample that no longer does (end None when the stream ends with it)."""

    def __init__(self) -> None:
        self._open: dict[str, float] = {}
        self._rows: list[tuple[str, float, float | None]] = []

    def feed(self, time: float, active: tuple[str, ...]) -> None:
        for name in [n for n in self._open if n not in active]:
            self._rows.append((name, self._open.pop(name), time))
        for name in active:
            self._open.setdefault(name, time)

    def timeline(self) -> tuple[tuple[str, float, float | None], ...]:
        rows = self._rows + [(name, start, None) for name, start in self._open.items()]
        return tuple(sorted(rows, key=lambda r: (r[1], r[0])))
