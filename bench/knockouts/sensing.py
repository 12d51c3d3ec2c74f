"""Knock-outs in what the navigator sees: its laser scans, made worse by a graded amount before
it reads them. Each changed scan is a new, read-only ``LaserScan``: the sensor's own array
(which the trace and the monitor record) is never touched."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from bench.knockouts.wrapper import Wrapper, seeded
from rei.runtime.messages import LaserScan
from rei.runtime.robot.contract import (
    Controller,
    ControllerContext,
    Observation,
    VelocityCommand,
    read_only_scan,
)


def _with_ranges(scan: LaserScan, ranges: np.ndarray) -> LaserScan | None:
    return read_only_scan(replace(scan, ranges=ranges))


class ScanFilter(Wrapper):
    """A wrapper that hands the navigator ``filtered(scan)`` for each scan, made once per scan:
    a scan handed again (the laser is slower than the control loop) has the same time stamp
    (without one: is the same object), and the navigator gets the same filtered object again
    (the reference reads each scan once, by identity; noise drawn anew each tick would be a
    different, milder defect)."""

    def __init__(self, name: str, inner: Controller) -> None:
        super().__init__(name, inner)
        self._raw: LaserScan | None = None
        self._raw_time: float | None = None
        self._filtered: LaserScan | None = None

    def reset(self, context: ControllerContext) -> None:
        self._raw, self._raw_time, self._filtered = None, None, None
        super().reset(context)

    def filtered(self, scan: LaserScan) -> LaserScan | None:
        raise NotImplementedError

    def step(self, observation: Observation) -> VelocityCommand:
        scan = observation.scan
        if scan is None:
            seen = None
        else:
            same = (observation.scan_time == self._raw_time
                    if observation.scan_time is not None else scan is self._raw)
            if self._raw is None or not same:
                self._raw, self._raw_time = scan, observation.scan_time
                self._filtered = self.filtered(scan)
            seen = self._filtered
        return super().step(replace(observation, scan=seen))


class LaserNoise(ScanFilter):
    """Defect: every range the laser returned (a hit, not a max-range "nothing") gets extra
    Gaussian noise of standard deviation ``millimetres`` mm, drawn once per scan from the
    run's seed; a range pushed beyond the laser's limits is clipped to them (beyond the
    maximum: nothing seen).

    Imitates: a dirty or fogged scanner window, a cheaper laser than the one the stack was
    tuned for, or a scan filter that adds jitter (an interpolating resampler).

    Expected catcher: the collision requirements and the geometric laser checks
    (GEOM_CLOSE_LASER_CORRECT, GEOM_COLLISION_LASER_CORRECT) when points jump towards or
    away from the robot near obstacles; SMOOTH_MOTION, EFFICIENT_PATH and TIME_TO_GOAL when
    phantom points make it weave, slow down or detour.
    """

    def __init__(self, name: str, inner: Controller, millimetres: int) -> None:
        super().__init__(name, inner)
        self.sigma = millimetres / 1000
        self._rng = np.random.default_rng(0)

    def reset(self, context: ControllerContext) -> None:
        self._rng = seeded(context, "laser-noise")
        super().reset(context)

    def filtered(self, scan: LaserScan) -> LaserScan | None:
        ranges = np.array(scan.ranges, dtype=float)
        noise = self._rng.normal(0.0, self.sigma, ranges.shape)  # every beam: same draws
        hit = np.isfinite(ranges) & (ranges >= scan.range_min) & (ranges < scan.range_max)
        ranges[hit] = np.clip(ranges[hit] + noise[hit], scan.range_min, scan.range_max)
        return _with_ranges(scan, ranges)


def blinded(scan: LaserScan, width: float) -> LaserScan | None:
    """``scan`` with every beam within ``width / 2`` radians of straight ahead (the laser's
    bearing 0) reading the maximum range."""
    ranges = np.array(scan.ranges, dtype=float)
    bearings = scan.angle_min + scan.angle_increment * np.arange(len(ranges))
    ahead = np.abs(np.remainder(bearings + math.pi, 2 * math.pi) - math.pi)
    ranges[ahead <= width / 2 + 1e-9] = scan.range_max
    return _with_ranges(scan, ranges)


class BlindSector(ScanFilter):
    """Defect: a sector ``degrees`` wide straight ahead of the laser reads maximum range
    (nothing seen) in every scan.

    Imitates: a mounting bracket, a bumper or a cable in front of the scanner window masked
    out with a too-wide angular-bounds filter, or a scanner window scratched in the middle.

    Expected catcher: the collision requirements (NO_ROBOT_COLLISION, MISSION_SIMPLE,
    MISSION_WITH_HUMAN_TRAJECTORY) and REACTION_TIME, HUMAN_SLOW_ZONE when what it should
    avoid is straight ahead and not on the static map (people, moving or unmapped objects).
    """

    def __init__(self, name: str, inner: Controller, degrees: int) -> None:
        super().__init__(name, inner)
        self.width = math.radians(degrees)

    def filtered(self, scan: LaserScan) -> LaserScan | None:
        return blinded(scan, self.width)
