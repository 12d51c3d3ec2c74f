"""What the `reference` navigator makes of its laser: the points near it in its own frame, from
the odometry pose the scan was taken at, and which of them the static map does not explain (a
person, a moving object: ``UNMAPPED_BEYOND``, ``SHADOW_TOLERANCE``), for the slow zone.

``LaserView`` is a part of ``ReferenceNavigator`` (runtime/robot/navigator/reference.py), not
a navigator of its own: ``ReferenceNavigator.reset`` sets the state it reads, and a subclass
of the navigator overrides its methods as before (bench/defects' ignores-humans, no-slow-zone).
This module must never import pybullet.
"""

from __future__ import annotations

import math

import numpy as np

from rei.runtime.messages import LaserScan
from rei.runtime.robot.contract import ControllerContext, Observation
from rei.runtime.robot.navigator.clearance import clearance_field
from rei.runtime.robot.navigator.mapcast import MapCaster
from rei.runtime.robot.navigator.tuning import ReferenceTuning


class LaserView:
    """The laser points of the current scan, mapped or unmapped (computed once per scan)."""

    tuning: ReferenceTuning
    slow_zone_reach: float
    _ctx: ControllerContext | None
    _half: tuple[float, float]
    _odometry: list[tuple[float, tuple[float, float, float]]]
    _scan_pose: tuple[float, float, float]
    _points_of: LaserScan | None
    _points: np.ndarray
    _trig_key: tuple[float, float, int] | None
    _near_of: np.ndarray | None
    _near: np.ndarray

    def _build_map_fit(self, ctx: ControllerContext) -> None:
        """The fine distance-to-map grid that tells mapped laser points from unmapped ones."""
        t = self.tuning
        x0, y0, x1, y1 = ctx.bounds
        nx_ = int(math.ceil((x1 - x0) / t.map_fit_res))
        ny_ = int(math.ceil((y1 - y0) / t.map_fit_res))
        xs = x0 + (np.arange(nx_) + 0.5) * t.map_fit_res
        ys = y0 + (np.arange(ny_) + 0.5) * t.map_fit_res
        self._fit = clearance_field(xs, ys, ctx, t.unmapped_beyond + 0.05)
        self._caster = MapCaster(ctx.obstacles, grow=t.shadow_graze)

    def _unmapped(self, points: np.ndarray, pose: tuple[float, float, float]) -> np.ndarray:
        """Which laser points (robot frame) the static map does not explain: farther than
        ``UNMAPPED_BEYOND`` from it, or nearer, but where the map leaves the beam free for
        more than ``SHADOW_TOLERANCE`` beyond them (something in front of the map)."""
        if not len(points):
            return np.zeros(0, dtype=bool)
        t = self.tuning
        x, y, yaw = pose
        c, s = math.cos(yaw), math.sin(yaw)
        wx = x + c * points[:, 0] - s * points[:, 1]
        wy = y + s * points[:, 0] + c * points[:, 1]
        x0, y0 = self._ctx.bounds[:2]  # type: ignore[union-attr]
        i = np.clip(np.floor((wx - x0) / t.map_fit_res).astype(np.int64), 0,
                    self._fit.shape[0] - 1)
        j = np.clip(np.floor((wy - y0) / t.map_fit_res).astype(np.int64), 0,
                    self._fit.shape[1] - 1)
        far: np.ndarray = self._fit[i, j] > t.unmapped_beyond
        explained = np.nonzero(~far)[0]
        if len(explained):
            # Near the map, but is it the map the beam stopped at? A person standing against
            # a wall or a pillar is within UNMAPPED_BEYOND of it, on the robot's side.
            laser = self._ctx.laser  # type: ignore[union-attr]
            mx = x + c * laser.mount_x - s * laser.mount_y
            my = y + s * laser.mount_x + c * laser.mount_y
            beams = np.stack((wx[explained] - mx, wy[explained] - my), axis=1)
            measured = np.hypot(beams[:, 0], beams[:, 1])
            expected = self._caster.ranges((mx, my), beams / measured[:, None].clip(1e-9),
                                           float(measured.max()) + t.shadow_tolerance)
            far[explained] = expected > measured + t.shadow_tolerance
        return far

    def _in_slow_zone(self, pose: tuple[float, float, float], points: np.ndarray) -> bool:
        """Whether an unmapped laser point is within the slow zone (and its lead)."""
        if not len(points):
            return False
        if self._near_of is not points:  # the points near the footprint: once per scan
            # The gap to the robot's own footprint from outside, in its frame: no yaw and no
            # inside term, so not geometry.box_distance's operations (kept as they were).
            hx, hy = self._half
            qx = np.abs(points[:, 0]) - hx
            qy = np.abs(points[:, 1]) - hy
            gap = np.hypot(np.maximum(qx, 0.0), np.maximum(qy, 0.0))
            self._near_of, self._near = points, points[gap < self.slow_zone_reach]
        return bool(self._unmapped(self._near, pose).any())

    def _laser_points(self, observation: Observation) -> np.ndarray:
        """Laser endpoints near the robot, in the robot's frame (computed once per scan)."""
        scan = observation.scan
        if scan is None:
            return np.zeros((0, 2))
        if scan is self._points_of:
            return self._points
        r = scan.ranges
        key = (scan.angle_min, scan.angle_increment, len(r))
        if self._trig_key != key:
            angles = scan.angle_min + scan.angle_increment * np.arange(len(r))
            self._trig = (np.cos(angles), np.sin(angles))
            self._trig_key = key
        cos, sin = self._trig
        keep = (r < min(self.tuning.sense_radius, scan.range_max - 1e-6)) & (r >= scan.range_min)
        mx, my = self._ctx.laser.mount_x, self._ctx.laser.mount_y  # type: ignore[union-attr]
        self._points_of = scan
        self._scan_pose = self._pose_at(observation.scan_time, observation.odom_pose)
        self._points = np.stack((mx + r[keep] * cos[keep], my + r[keep] * sin[keep]), axis=1)
        return self._points

    def _pose_at(self, time: float | None,
                 now: tuple[float, float, float]) -> tuple[float, float, float]:
        """The odometry pose at ``time`` (a scan's), interpolated between the steps around
        it; ``now`` when it is unknown or later than the last step, the oldest kept pose
        when it is older. A scan is up to a laser period old when it is acted on: read from
        the pose of the step, a wall 0.26 m/s x 0.2 s behind the robot came 5 cm nearer than
        the map, beyond ``SHADOW_TOLERANCE``, and seemed a person (a stack transforms a scan
        with the pose at its own time stamp)."""
        history = self._odometry
        if time is None or not history or time >= history[-1][0]:
            return now
        if time <= history[0][0]:
            return history[0][1]
        k = next(i for i, (t, _) in enumerate(history) if t >= time)
        (t0, p0), (t1, p1) = history[k - 1], history[k]
        f = (time - t0) / (t1 - t0)
        dyaw = math.remainder(p1[2] - p0[2], math.tau)
        return (p0[0] + f * (p1[0] - p0[0]), p0[1] + f * (p1[1] - p0[1]),
                math.remainder(p0[2] + f * dyaw, math.tau))
