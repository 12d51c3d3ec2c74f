"""The faults component: the fault stage (``rei.runtime.simulation.faults.stage``) between the
sensors
and the robot under test.

Every control tick, before the mission executor and the robot, it asks the stage what the
robot sees (the latest measured scan, then odometry) and publishes that as the robot's
view, which is also what the collector records as the belief. At a sample between control
ticks after a newer scan, it asks again (the stage answers the same object for a scan it
already changed), so the belief never lags the sensor by a tick. After each sample it hands
the signals the monitor fired to the stage. The motor side (``FaultStage.command``) is the
robot component's. The ground truth never passes through here.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

from rei.runtime.messages import RobotView, SignalFired
from rei.runtime.simulation.faults.stage import FaultStage, active_at
from rei.runtime.simulation.loop.board import Board
from rei.runtime.simulation.loop.scheduler import Clock


@runtime_checkable
class SignalSource(Protocol):
    """A sink that fires ``.vepl`` signals (the live monitor) and tells listeners."""

    def listen(self, listener: Callable[[str, float], None]) -> None: ...


@dataclass(frozen=True)
class Faults:
    stage: FaultStage

    def start(self, board: Board) -> FaultsRun:
        return FaultsRun(self, board)


class FaultsRun:
    def __init__(self, spec: Faults, board: Board) -> None:
        self.stage, self.board = spec.stage, board
        self._names = tuple(name for name, _ in spec.stage.described())
        quick = getattr(spec.stage, "active_now", None)
        self._active: Callable[[float], tuple[str, ...]] = quick if callable(quick) else (
            lambda now: active_at(self.stage.timeline(), now, self._names))
        self._seq = 0
        self._signal_seq = 0
        self._measured: object = None
        """The measured scan the stage last saw (identity: one stage call per scan)."""

    def heard(self, name: str, time: float) -> None:
        """A signal fired (the monitor's listener): queued until after the sample."""
        self.board.signals.append(SignalFired(self._signal_seq, time, name))
        self._signal_seq += 1

    def step(self, clock: Clock) -> None:
        """The control tick: scan, then odometry, through the stage."""
        board, now = self.board, clock.now
        reading = board.scan
        scan, at = self.stage.scan(now, None if reading is None else reading.scan,
                                   None if reading is None else reading.time)
        self._measured = reading
        odometry = board.odometry
        assert odometry is not None
        pose, twist = self.stage.odometry(now, odometry.pose, odometry.twist)
        board.view = RobotView(self._seq, now, scan, at, pose, twist)
        self._seq += 1
        if self._names:
            board.faults = self._active(now)

    def refresh(self, clock: Clock) -> None:
        """At a sample: the view of a scan measured since the last control tick."""
        board = self.board
        reading, view = board.scan, board.view
        if reading is None or reading is self._measured or view is None:
            return
        scan, at = self.stage.scan(clock.now, reading.scan, reading.time)
        self._measured = reading
        board.view = RobotView(self._seq, clock.now, scan, at, view.odom, view.odom_twist)
        self._seq += 1

    def deliver(self, clock: Clock) -> None:
        """After a sample: the signals fired at it, in firing order."""
        signals = self.board.signals
        if signals:
            for s in signals:
                self.stage.signal(s.time, s.name)
            signals.clear()
