"""The laser component: a 2D scan from the robot's true pose at the laser's rate.

Walls and static objects are a fixed shape set built once per run; the moving bodies the
scan plane cuts are added from the world's object states of the same tick. The noise draws
from the run's main random stream (shared with odometry, in that order within a tick).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rei.runtime.artifacts.world import WorldManifest
from rei.runtime.messages import LaserScan, ScanReading
from rei.runtime.raycast import scene_shapes, shapes_of
from rei.runtime.simulation.loop.board import Board
from rei.runtime.simulation.loop.scheduler import Clock
from rei.runtime.simulation.sensors.laser import Laser2D


@dataclass(frozen=True)
class Laser:
    manifest: WorldManifest
    noise: float
    """Standard deviation (m) of the range error."""

    @property
    def moving_seen(self) -> tuple[int, ...]:
        """Indices into the manifest's objects of the moving bodies the scan plane cuts."""
        plane = self.manifest.laser.mount_z
        return tuple(i for i, b in enumerate(self.manifest.objects)
                     if not b.fixed and b.height > plane)

    def start(self, board: Board, rng: np.random.Generator) -> LaserRun:
        return LaserRun(self, board, rng)


class LaserRun:
    def __init__(self, spec: Laser, board: Board, rng: np.random.Generator) -> None:
        manifest = spec.manifest
        self.spec, self.board, self.rng = spec, board, rng
        self.laser_spec = manifest.laser
        self.laser = Laser2D(manifest.laser,
                             scene_shapes(manifest, [b for b in manifest.objects if b.fixed]))
        self.seen = spec.moving_seen
        self.seen_specs = [manifest.objects[i] for i in self.seen]
        self.rows = list(self.seen)
        self.min_range = math.inf
        self._seq = 0

    def step(self, clock: Clock) -> None:
        board = self.board
        assert board.truth is not None  # the world publishes first
        moving = None
        if self.seen:
            assert board.bodies is not None
            moving = shapes_of(self.seen_specs, board.bodies.poses[self.rows])
        ranges = self.laser.scan(board.truth.pose, moving, self.rng, self.spec.noise)
        ranges.flags.writeable = False  # what was measured; sinks keep it
        self.min_range = min(self.min_range, float(ranges.min()))
        spec = self.laser_spec
        board.scan = ScanReading(self._seq, clock.now,
                                 LaserScan(self.laser.angle_min, self.laser.angle_increment,
                                           spec.min_range, spec.max_range, ranges))
        self._seq += 1
