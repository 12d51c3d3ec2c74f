"""Synthetic sample streams for monitor tests: a header and samples from robot poses."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from rei.catalogue import Box, Cylinder
from rei.runtime.messages import (
    SCHEMA_VERSION,
    LaserScan,
    MissionEvent,
    NavState,
    ObservedObject,
    RobotBelief,
    Sample,
    StreamHeader,
)

ROBOT = ObservedObject("waffle", "static", "turtlebot3_waffle", Box(0.281, 0.306), 0.2)


def wall(name: str, x: float, y: float) -> tuple[ObservedObject, tuple[float, float, float]]:
    return ObservedObject(name, "wall", "wall", Box(1.0, 1.0), 1.0), (x, y, 0.0)


def human(name: str, x: float, y: float) -> tuple[ObservedObject, tuple[float, float, float]]:
    return ObservedObject(name, "human", "human", Cylinder(0.25), 1.7), (x, y, 0.0)


def header(objects: Sequence[ObservedObject], floors: tuple[tuple[str, float, float], ...] = ()
           ) -> StreamHeader:
    return StreamHeader(SCHEMA_VERSION, "synthetic", "synthetic", 0, 10.0, ROBOT,
                        tuple(objects), 1.0, floors)


def forward_scan(forward: float) -> LaserScan:
    """A 4-beam scan (back, right, forward, left) whose forward beam reads ``forward``; the
    others see nothing."""
    return LaserScan(-np.pi, np.pi / 2, 0.12, 3.5, np.array([3.5, 3.5, forward, 3.5]))


def sample(seq: int, time: float, pose: tuple[float, float, float], poses: np.ndarray,
           laser_min: float = 3.5, events: tuple[MissionEvent, ...] = (),
           scan: LaserScan | None = None) -> Sample:
    belief = RobotBelief(pose, (0.0, 0.0), laser_min, scan, NavState.ACTIVE, None)
    n = len(poses)
    return Sample(seq, time, pose, (0.0, 0.0, 0.0), np.asarray(poses, dtype=float).reshape(n, 3),
                  np.zeros((n, 3)), belief, events)


def drive(placed: Sequence[tuple[ObservedObject, tuple[float, float, float]]],
          robot_poses: Sequence[tuple[float, float, float]], rate: float = 10.0,
          laser: Sequence[float] | None = None,
          events: dict[int, tuple[MissionEvent, ...]] | None = None
          ) -> tuple[StreamHeader, list[Sample]]:
    """A header and one sample per robot pose, 1/rate seconds apart, objects standing still.
    With ``laser``, every sample carries a new scan whose forward beam reads that range from
    the laser at the footprint's centre (the header's mount)."""
    h = header([o for o, _ in placed])
    poses = np.array([p for _, p in placed], dtype=float).reshape(len(placed), 3)
    samples = []
    for i, pose in enumerate(robot_poses):
        lm = laser[i] if laser is not None else 3.5
        scan = forward_scan(lm) if laser is not None else None
        samples.append(sample(i, i / rate, pose, poses, lm, (events or {}).get(i, ()), scan))
    return h, samples


def straight(x0: float, x1: float, n: int) -> list[tuple[float, float, float]]:
    return [(x0 + (x1 - x0) * i / (n - 1), 0.0, 0.0) for i in range(n)]


