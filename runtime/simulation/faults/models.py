"""The run-time models of the faults: per-run state behind each ``FaultDefinition``.

Every model is fed everything its channel carries, active or not (a delay buffers scans
before it starts; odometry keeps an offset after a jump), and draws from its own seeded
generator the same way whether it is active or not, so switching one fault on or off never
shifts another's draws. Semantics, and where the thesis left a choice, in docs/faults.md.
This module must never import pybullet.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import replace
from typing import Protocol

import numpy as np

from rei.lang.mission.faults import FaultDefinition
from rei.runtime.messages import LaserScan
from rei.runtime.simulation.faults.activation import ActivationTracker
from rei.runtime.simulation.faults.stage import Command, Pose, Twist

STOP: Command = (0.0, 0.0)
EPS = 1e-9
"""Seconds: times closer than this are the same instant (ticks are sums of float steps)."""


def _with_ranges(scan: LaserScan, ranges: np.ndarray) -> LaserScan:
    """A copy of ``scan`` with new ranges, clipped to the scanner's limits."""
    return replace(scan, ranges=np.clip(ranges, scan.range_min, scan.range_max))


class ScanModel(Protocol):
    time_driven: bool
    """False: called once per new input (what the previous model passed on); True: called
    at every control tick (its output changes with time alone, as a delay's does)."""

    def apply(self, time: float, scan: LaserScan, stamp: float
              ) -> tuple[LaserScan | None, float | None]: ...


class OdometryModel(Protocol):
    def apply(self, time: float, pose: Pose, twist: Twist) -> tuple[Pose, Twist]: ...


class CommandModel(Protocol):
    def apply(self, time: float, command: Command) -> Command: ...


class LaserPoisson:
    """The thesis's error-prone laser (7.5, Figures 38-39): a Poisson process of ``rate``
    occurrences per second, counted only while the fault is active and its impulse (period,
    pulse width ``width`` x period, starting ``phase`` after the fault became active) is high.
    A scan with k >= 1 occurrences since the previous scan is replaced by the previous reading
    with ``gain`` x k metres added to every range (then clipped to the scanner's limits)."""

    time_driven = False

    def __init__(self, d: FaultDefinition, when: ActivationTracker,
                 rng: np.random.Generator) -> None:
        self.rate, self.gain = d.value("rate"), d.value("gain")
        self.period, self.width, self.phase = d.value("period"), d.value("width"), d.value("phase")
        self.when, self.rng = when, rng
        self.previous: LaserScan | None = None
        self.previous_stamp: float | None = None
        self.occurrences = 0
        """Occurrences counted so far (while active and the impulse was high)."""
        self.corrupted = 0
        """Scans replaced by a noisy previous reading."""

    def pulse_high(self, time: float) -> bool:
        since = self.when.since(time)
        if since is None:
            return False
        into = time - since - self.phase
        return into >= -EPS and math.fmod(max(into, 0.0), self.period) < self.width * self.period

    def pulses(self, start: float, end: float | None, now: float
               ) -> list[tuple[float, float | None]]:
        """The impulse's high phases within the activation (start, end) as of ``now`` (end
        None: still active): when the fault actually lies; the timeline, the samples and
        events.csv show these. A phase still high at ``now`` has end None."""
        if self.width >= 1.0 and self.phase == 0.0:
            return [(start, end)]  # always high: one phase, the activation itself
        out: list[tuple[float, float | None]] = []
        high = self.width * self.period
        a = start + self.phase
        while a <= now and (end is None or a < end):
            b = a + high
            if end is not None:
                out.append((a, min(b, end)))
            else:
                out.append((a, b if b <= now else None))
            a += self.period
        return out

    def apply(self, time: float, scan: LaserScan, stamp: float
              ) -> tuple[LaserScan | None, float | None]:
        start = self.previous_stamp if self.previous_stamp is not None else min(0.0, stamp)
        span = max(stamp - start, 0.0)
        # A Poisson process on (start, stamp]: the count, then the times, uniform given it.
        times = np.sort(start + span * (1.0 - self.rng.random(int(self.rng.poisson(
            self.rate * span)))))
        counted = [float(t) for t in times if self.pulse_high(float(t))]
        self.occurrences += len(counted)
        previous = self.previous
        self.previous, self.previous_stamp = scan, stamp
        if not counted or previous is None:
            return scan, stamp
        self.corrupted += 1
        return _with_ranges(scan, previous.ranges + self.gain * len(counted)), stamp


class LaserNoise:
    """Gaussian noise of ``sigma`` metres on every range that hit something."""

    time_driven = False

    def __init__(self, d: FaultDefinition, when: ActivationTracker,
                 rng: np.random.Generator) -> None:
        self.sigma, self.when, self.rng = d.value("sigma"), when, rng

    def apply(self, time: float, scan: LaserScan, stamp: float
              ) -> tuple[LaserScan | None, float | None]:
        noise = self.rng.normal(0.0, self.sigma, size=scan.ranges.shape)
        if not self.when.active(time):
            return scan, stamp
        hit = scan.ranges < scan.range_max
        return _with_ranges(scan, np.where(hit, scan.ranges + noise, scan.ranges)), stamp


class LaserDropout:
    """Each beam independently, with probability ``share``, reads the maximum range: the
    REI (and LDS-01 driver) convention for 'nothing returned', so no consumer meets NaN."""

    time_driven = False

    def __init__(self, d: FaultDefinition, when: ActivationTracker,
                 rng: np.random.Generator) -> None:
        self.share, self.when, self.rng = d.value("share"), when, rng
        self.dropped = 0
        self.beams = 0

    def apply(self, time: float, scan: LaserScan, stamp: float
              ) -> tuple[LaserScan | None, float | None]:
        lost = self.rng.random(scan.ranges.shape) < self.share
        if not self.when.active(time):
            return scan, stamp
        self.dropped += int(lost.sum())
        self.beams += lost.size
        return _with_ranges(scan, np.where(lost, scan.range_max, scan.ranges)), stamp


class LaserFreeze:
    """While active the robot keeps getting the scan (and stamp) it had when the fault
    started; from the start of the run, the first scan measured."""

    time_driven = False

    def __init__(self, d: FaultDefinition, when: ActivationTracker,
                 rng: np.random.Generator) -> None:
        self.when = when
        self.last: tuple[LaserScan, float] | None = None
        self.frozen: tuple[LaserScan, float] | None = None
        self.frozen_since: float | None = None

    def apply(self, time: float, scan: LaserScan, stamp: float
              ) -> tuple[LaserScan | None, float | None]:
        since = self.when.since(time)
        if since is None:
            self.frozen = self.frozen_since = None
            self.last = (scan, stamp)
            return scan, stamp
        if self.frozen is None or self.frozen_since != since:
            self.frozen, self.frozen_since = self.last or (scan, stamp), since
        self.last = self.frozen
        return self.frozen


class LaserDelay:
    """While active the robot gets the newest scan measured at least ``seconds`` before now
    (none while no scan is that old), with its own stamp. Called at every tick: what it
    delivers changes with time, not only when a scan is measured."""

    time_driven = True

    def __init__(self, d: FaultDefinition, when: ActivationTracker,
                 rng: np.random.Generator) -> None:
        self.seconds, self.when = d.value("seconds"), when
        self.buffer: deque[tuple[float, LaserScan]] = deque()

    def apply(self, time: float, scan: LaserScan, stamp: float
              ) -> tuple[LaserScan | None, float | None]:
        if not self.buffer or self.buffer[-1][1] is not scan:
            self.buffer.append((stamp, scan))
        cutoff = time - self.seconds + EPS
        while len(self.buffer) > 1 and self.buffer[1][0] <= cutoff:
            self.buffer.popleft()  # a newer scan is old enough: this one is never delivered
        if not self.when.active(time):
            return scan, stamp
        oldest_stamp, oldest = self.buffer[0]
        if oldest_stamp > cutoff:
            return None, None
        return oldest, oldest_stamp


class LaserSector:
    """Beams whose bearing (scanner frame) lies in [min_deg, max_deg] read ``distance``."""

    time_driven = False

    def __init__(self, d: FaultDefinition, when: ActivationTracker,
                 rng: np.random.Generator) -> None:
        self.low, self.high = d.value("min_deg"), d.value("max_deg")
        self.distance, self.when = d.value("distance"), when

    def covers(self, scan: LaserScan) -> np.ndarray:
        """Which beams of ``scan`` the sector covers."""
        bearing = np.degrees(scan.angle_min + scan.angle_increment * np.arange(len(scan.ranges)))
        if self.high - self.low >= 360.0:
            return np.ones(len(scan.ranges), dtype=bool)
        inside: np.ndarray = np.mod(bearing - self.low, 360.0) <= (self.high - self.low) + EPS
        return inside

    def apply(self, time: float, scan: LaserScan, stamp: float
              ) -> tuple[LaserScan | None, float | None]:
        if not self.when.active(time):
            return scan, stamp
        return _with_ranges(scan, np.where(self.covers(scan), self.distance, scan.ranges)), stamp


def _motion(last: Pose, pose: Pose) -> tuple[float, float, float]:
    """(forward, sideways, turn) from ``last`` to ``pose``, in ``last``'s frame."""
    c, s = math.cos(last[2]), math.sin(last[2])
    dx, dy = pose[0] - last[0], pose[1] - last[1]
    return c * dx + s * dy, -s * dx + c * dy, math.remainder(pose[2] - last[2], math.tau)


class OdomDrift:
    """While active, each step travelled is reported (1 + ``scale``) times as long, the
    heading turns ``yaw_per_metre`` degrees more per metre, and the position random-walks
    ``walk`` metres per sqrt(second) per axis. The error stays after the fault ends: odometry
    integrates from what it reported, as dead reckoning does."""

    def __init__(self, d: FaultDefinition, when: ActivationTracker,
                 rng: np.random.Generator) -> None:
        self.scale, self.walk = d.value("scale"), d.value("walk")
        self.yaw_per_metre = math.radians(d.value("yaw_per_metre"))
        self.when, self.rng = when, rng
        self.last: tuple[float, Pose] | None = None
        self.reported: Pose | None = None
        """What odometry reports once the fault acted (None: it never did)."""

    def apply(self, time: float, pose: Pose, twist: Twist) -> tuple[Pose, Twist]:
        step = self.rng.normal(0.0, 1.0, size=2)
        last, self.last = self.last, (time, pose)
        active = self.when.active(time)
        if last is None or (self.reported is None and not active):
            return pose, twist
        fwd, side, turn = _motion(last[1], pose)
        base = self.reported if self.reported is not None else last[1]
        if active:
            distance = math.hypot(fwd, side)
            fwd, side = fwd * (1.0 + self.scale), side * (1.0 + self.scale)
            turn += self.yaw_per_metre * distance
        c, s = math.cos(base[2]), math.sin(base[2])
        x, y = base[0] + c * fwd - s * side, base[1] + s * fwd + c * side
        if active and self.walk > 0.0:
            spread = self.walk * math.sqrt(max(time - last[0], 0.0))
            x, y = x + spread * float(step[0]), y + spread * float(step[1])
        self.reported = (x, y, math.remainder(base[2] + turn, math.tau))
        if active:
            twist = (twist[0] * (1.0 + self.scale),
                     twist[1] + self.yaw_per_metre * abs(twist[0]))
        return self.reported, twist


class OdomJump:
    """When the fault becomes active, odometry jumps by (dx, dy) metres and ``dyaw`` degrees
    in its own frame, and integrates on from there (the offset stays after the fault ends;
    every new activation jumps again)."""

    def __init__(self, d: FaultDefinition, when: ActivationTracker,
                 rng: np.random.Generator) -> None:
        self.dx, self.dy, self.dyaw = d.value("dx"), d.value("dy"), math.radians(d.value("dyaw"))
        self.when = when
        self.transform = (0.0, 0.0, 0.0)
        """(tx, ty, theta): reported = R(theta) measured + t."""
        self.jumped_for: float | None = None
        self.jumps = 0

    def _report(self, pose: Pose) -> Pose:
        tx, ty, th = self.transform
        c, s = math.cos(th), math.sin(th)
        return (c * pose[0] - s * pose[1] + tx, s * pose[0] + c * pose[1] + ty,
                math.remainder(pose[2] + th, math.tau))

    def apply(self, time: float, pose: Pose, twist: Twist) -> tuple[Pose, Twist]:
        since = self.when.since(time)
        if since is not None and since != self.jumped_for:
            self.jumped_for = since
            self.jumps += 1
            # Turn by dyaw about the reported point, then shift: reported' = J(reported).
            rx, ry, _ = self._report(pose)
            tx, ty, th = self.transform
            c, s = math.cos(self.dyaw), math.sin(self.dyaw)
            ntx = c * (tx - rx) - s * (ty - ry) + rx + self.dx
            nty = s * (tx - rx) + c * (ty - ry) + ry + self.dy
            self.transform = (ntx, nty, th + self.dyaw)
        if self.transform == (0.0, 0.0, 0.0):
            return pose, twist
        return self._report(pose), twist


class CmdDrop:
    """While active each command is lost with probability ``share``: the motors keep the
    previous command that reached them (as a ROS base controller keeps its last cmd_vel),
    a stop before any reached them."""

    def __init__(self, d: FaultDefinition, when: ActivationTracker,
                 rng: np.random.Generator) -> None:
        self.share, self.when, self.rng = d.value("share"), when, rng
        self.last: Command = STOP
        self.asked = 0
        self.lost = 0

    def apply(self, time: float, command: Command) -> Command:
        lose = self.rng.random() < self.share
        if self.when.active(time):
            self.asked += 1
            if lose:
                self.lost += 1
                return self.last
        self.last = command
        return command


class CmdDelay:
    """While active the motors get the newest command asked for at least ``seconds`` before
    now; a stop while none is that old."""

    def __init__(self, d: FaultDefinition, when: ActivationTracker,
                 rng: np.random.Generator) -> None:
        self.seconds, self.when = d.value("seconds"), when
        self.buffer: deque[tuple[float, Command]] = deque()

    def apply(self, time: float, command: Command) -> Command:
        self.buffer.append((time, command))
        cutoff = time - self.seconds + EPS
        while len(self.buffer) > 1 and self.buffer[1][0] <= cutoff:
            self.buffer.popleft()
        if not self.when.active(time):
            return command
        asked_at, old = self.buffer[0]
        return old if asked_at <= cutoff else STOP


SCAN_MODELS = {"laser_poisson": LaserPoisson, "laser_noise": LaserNoise,
               "laser_dropout": LaserDropout, "laser_freeze": LaserFreeze,
               "laser_delay": LaserDelay, "laser_sector": LaserSector}
ODOMETRY_MODELS = {"odom_drift": OdomDrift, "odom_jump": OdomJump}
COMMAND_MODELS = {"cmd_drop": CmdDrop, "cmd_delay": CmdDelay}
