"""The collector component: the data collector (thesis 6.1.2) feeding the run's sinks.

At its sample rate, and in the tick the run ends, it takes the mission's events since the
previous sample and builds a ``Sample`` of the ground truth (the world's states, with the
bodies touched since the previous sample) and
the robot's belief (the robot's view, its navigation state and the command it asked for)
and hands it to the sinks: the trace, the live monitor, any other.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rei.runtime.artifacts.world import WorldManifest
from rei.runtime.messages import NavState, Pose, StreamHeader
from rei.runtime.messages.sink import SampleSink
from rei.runtime.simulation.loop.board import Board
from rei.runtime.simulation.loop.scheduler import Clock
from rei.runtime.simulation.sampler import DataCollector


@dataclass(frozen=True)
class Collector:
    header: StreamHeader
    manifest: WorldManifest
    sinks: tuple[SampleSink, ...]
    every: int
    """Physics steps between samples."""
    origin: Pose
    """Odometry's belief before its first reading (the start pose)."""

    def start(self, board: Board) -> CollectorRun:
        return CollectorRun(self, board)


class CollectorRun:
    def __init__(self, spec: Collector, board: Board) -> None:
        self.spec, self.board = spec, board
        manifest = spec.manifest
        self.collector = DataCollector(spec.header, list(spec.sinks), manifest.laser.max_range)
        n_walls = len(manifest.walls)
        self.poses = np.array([(b.x, b.y, b.yaw) for b in manifest.observed],
                              dtype=float).reshape(-1, 3)
        self.twists = np.zeros_like(self.poses)
        self.moving = [i for i, b in enumerate(manifest.objects) if not b.fixed]
        self.rows = np.array([n_walls + i for i in self.moving], dtype=int)

    def open(self) -> None:
        """The stream header to the sinks (before the first tick)."""
        self.collector.start()

    def step(self, clock: Clock) -> None:
        board, collector, now = self.board, self.collector, clock.now
        for queued in board.events:
            collector.event(queued.events)
        board.events.clear()
        truth, bodies, view, status, command = (board.truth, board.bodies, board.view,
                                                board.status, board.command)
        assert truth is not None and bodies is not None and bodies.time == now
        if bodies.touched:
            collector.touch(bodies.touched)
        if len(self.rows):
            self.poses[self.rows] = bodies.poses[self.moving]
            self.twists[self.rows] = bodies.twists[self.moving]
        odom, odom_twist, scan, scan_time = ((self.spec.origin, (0.0, 0.0), None, None)
                                             if view is None else
                                             (view.odom, view.odom_twist, view.scan,
                                              view.scan_time))
        nav, task = (NavState.IDLE, None) if status is None else (status.nav_state, status.task)
        # Each sample owns its arrays: sinks may keep samples (the monitor's windows).
        collector.sample(now, truth.pose, bodies.robot_twist, self.poses.copy(),
                         self.twists.copy(), odom, odom_twist, scan, scan_time, nav, task,
                         (0.0, 0.0) if command is None else command.raw, board.faults)

    def finish(self, now: float, outcome: str, reason: str) -> None:
        self.collector.finish(now, outcome, reason)

    @property
    def samples(self) -> int:
        return self.collector.seq

