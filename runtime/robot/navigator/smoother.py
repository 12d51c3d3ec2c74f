"""The `reference` navigator's velocity smoother: what Nav2's ``nav2_velocity_smoother`` does
between its controller and the base (open loop), within the drive's acceleration limits.

Each control tick the command the navigator chose moves from the last command sent by at
most the drive's acceleration (speeding up) or deceleration (slowing down, or reversing)
times the time since, per axis, as Nav2's smoother decides it: a command of the same sign
and at least the last one's magnitude accelerates, anything else decelerates. The limits
are the catalogue's (``DriveSpec.max_linear_accel`` and the others), so the commands are
ones the base can follow (the default .vepl's COMMAND_ACCELERATION).

A smoother must never make the robot less safe. The navigator checked the command it chose
against the laser; a smoothed one lies between it and the last command and was not checked.
So ``braking_poses`` gives the path of driving a smoothed command for one control period and
then stopping at the deceleration limits (the worst the next tick can ask of it), and the
navigator sends the smoothed command only while that path keeps its margin from every laser
point; otherwise it sends the checked command unsmoothed (``bypass``), as Nav2's collision
monitor, downstream of its smoother, overrides it. This module must never import pybullet.
"""

from __future__ import annotations

import math

import numpy as np

from rei.catalogue.model import DriveSpec
from rei.runtime.robot.contract import STOP, ControllerContext, VelocityCommand
from rei.runtime.robot.navigator.recovery import poses_keep_clear

BRAKE_STEP = 0.02
"""Seconds between the poses of a braking path (the footprint moves ~5 mm, 0.04 rad)."""


def _limited(last: float, target: float, accel: float, decel: float, dt: float) -> float:
    """``target`` moved towards from ``last`` by at most the allowed change in ``dt``."""
    speeding_up = last * target >= 0.0 and abs(target) >= abs(last)
    step = (accel if speeding_up else decel) * dt
    return min(max(target, last - step), last + step)


class VelocitySmoother:
    """The last command sent and the limits each next one is kept within (per run)."""

    def __init__(self, drive: DriveSpec, period: float) -> None:
        self.drive = drive
        self.period = period
        """Seconds between control ticks: the step of the first command, and how long a
        command is held before the next can change it."""
        self.last = STOP
        self.time: float | None = None
        """When ``last`` was sent; None before the first command."""
        self.bypassed = 0
        """Commands sent unsmoothed because the smoothed one's braking path was not clear."""

    @classmethod
    def of_run(cls, context: ControllerContext) -> VelocitySmoother:
        """A smoother of the run's drive and control period."""
        return cls(context.drive, 1.0 / context.control_rate)

    def smoothed(self, target: VelocityCommand, time: float) -> VelocityCommand:
        """``target`` within the limits from the last command sent (not sent yet)."""
        dt = self.period if self.time is None else min(max(time - self.time, 0.0),
                                                       self.period * 10)
        d = self.drive
        return VelocityCommand(
            _limited(self.last.linear, target.linear, d.max_linear_accel, d.max_linear_decel,
                     dt),
            _limited(self.last.angular, target.angular, d.max_angular_accel,
                     d.max_angular_decel, dt))

    def sent(self, command: VelocityCommand, time: float, bypass: bool = False) -> VelocityCommand:
        """Record ``command`` as sent at ``time`` (``bypass``: unsmoothed, for safety)."""
        self.last, self.time = command, time
        self.bypassed += bypass
        return command

    def braking_poses(self, command: VelocityCommand) -> np.ndarray:
        """Poses (S, 3; robot frame now) of driving ``command`` for one period and then
        braking at the deceleration limits to a standstill."""
        d = self.drive
        v, w = command.linear, command.angular
        stop = max(abs(v) / d.max_linear_decel, abs(w) / d.max_angular_decel)
        steps = max(1, int(math.ceil((self.period + stop) / BRAKE_STEP)))
        ts = np.arange(1, steps + 1) * BRAKE_STEP
        braking = np.maximum(ts - self.period, 0.0)
        vs = np.sign(v) * np.maximum(abs(v) - d.max_linear_decel * braking, 0.0)
        ws = np.sign(w) * np.maximum(abs(w) - d.max_angular_decel * braking, 0.0)
        th = np.concatenate(([0.0], np.cumsum(ws * BRAKE_STEP)))
        # each step drives at its speed along the heading it started with (5 mm steps)
        x = np.concatenate(([0.0], np.cumsum(vs * np.cos(th[:-1]) * BRAKE_STEP)))
        y = np.concatenate(([0.0], np.cumsum(vs * np.sin(th[:-1]) * BRAKE_STEP)))
        return np.stack((x, y, th), axis=1)


def clear_to_brake(smoother: VelocitySmoother, command: VelocityCommand, points: np.ndarray,
                   half: tuple[float, float], margin: float) -> bool:
    """Whether ``command``'s braking path (``VelocitySmoother.braking_poses``) keeps the
    footprint (half sizes ``half``) ``margin`` from every laser point (robot frame), as a
    recovery motion must (``recovery.poses_keep_clear``)."""
    return not len(points) or poses_keep_clear(points, half, smoother.braking_poses(command),
                                               margin)


def smooth_safely(smoother: VelocitySmoother, command: VelocityCommand, time: float,
                  points: np.ndarray, half: tuple[float, float],
                  margin: float) -> VelocityCommand:
    """The command to send for the navigator's checked ``command``: smoothed when its
    braking path is clear of the laser points by ``margin``, else ``command`` itself."""
    smoothed = smoother.smoothed(command, time)
    if smoothed == command or clear_to_brake(smoother, smoothed, points, half, margin):
        return smoother.sent(smoothed, time)
    return smoother.sent(command, time, bypass=True)
