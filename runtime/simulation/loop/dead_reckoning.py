"""The odometry component: the robot's motion since the previous control tick, as its
wheels would report it (drifted when the run asks for drift; the drift draws from the run's
main random stream after the laser's draws of the same tick)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rei.runtime.messages import OdometryReading, Pose
from rei.runtime.simulation.loop.board import Board
from rei.runtime.simulation.loop.scheduler import Clock
from rei.runtime.simulation.sensors.odometry import Odometry


@dataclass(frozen=True)
class DeadReckoning:
    origin: Pose
    """The robot's start pose: odometry's origin."""
    drift: float
    """Relative standard deviation of the per-tick error (0: exact)."""
    period: float
    """Seconds between two updates (the control period)."""

    def start(self, board: Board, rng: np.random.Generator) -> DeadReckoningRun:
        return DeadReckoningRun(self, board, rng)


class DeadReckoningRun:
    def __init__(self, spec: DeadReckoning, board: Board, rng: np.random.Generator) -> None:
        self.spec, self.board = spec, board
        self.sensor = Odometry(spec.origin, spec.drift, rng)
        self._seq = 0

    def step(self, clock: Clock) -> None:
        assert self.board.truth is not None
        self.sensor.update(self.board.truth.pose, self.spec.period)
        self.board.odometry = OdometryReading(self._seq, clock.now, self.sensor.pose,
                                              self.sensor.twist)
        self._seq += 1
