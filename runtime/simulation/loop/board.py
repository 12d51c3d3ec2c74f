"""The board: the latest message of each topic of one run, which is all components share.

A component writes only its own topics and reads others' through here, never the other
component itself. State topics keep the latest message; event topics (mission events,
signals) queue until their reader takes them. A bus carrying the messages between
processes replaces this object and nothing else. ``None`` until the topic's first message.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from rei.runtime.messages import (
    BodyStates,
    BodyVelocities,
    CommandIssued,
    MissionStatus,
    OdometryReading,
    RobotTruth,
    RobotView,
    ScanReading,
    SignalFired,
    TrackedBodies,
)


@dataclass(slots=True)
class Board:
    """Per run: mutable on purpose (each field is replaced by its one writer)."""

    truth: RobotTruth | None = None
    """world, every physics step."""
    bodies: BodyStates | None = None
    """world, at the laser's ticks (when it sees moving bodies) and the collector's."""
    tracked: TrackedBodies | None = None
    """world, every control tick when there are animated bodies."""
    velocities: BodyVelocities | None = None
    """animator, every physics step."""
    scan: ScanReading | None = None
    """laser, at its rate."""
    odometry: OdometryReading | None = None
    """odometry, every control tick."""
    view: RobotView | None = None
    """faults, every control tick (and at a sample after a newer scan)."""
    status: MissionStatus | None = None
    """mission, every control tick (its navigation state is what the collector records)."""
    events: list[MissionStatus] = field(default_factory=list)
    """mission's statuses that carried events, queued until the collector takes them (every
    event must reach it, even two in one tick)."""
    command: CommandIssued | None = None
    """robot, every control tick."""
    faults: tuple[str, ...] = ()
    """faults, every control tick and after each sample: the faults active now."""
    signals: list[SignalFired] = field(default_factory=list)
    """monitor's signals, queued until the fault stage takes them (after each sample)."""
