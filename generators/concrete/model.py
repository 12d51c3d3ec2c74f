"""Typed, immutable records of the concrete world and mission (metres, seconds, radians)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

from rei.catalogue import ObjectType
from rei.lang.mission.faults import FaultDefinition
from rei.lang.mission.model import COLLECTED_DATA, DEFAULT_HEADING_TOLERANCE, DEFAULT_SAMPLE_RATE
from rei.lang.room.model import DEFAULT_BEHAVIOUR, Behaviour

Role = Literal["static", "dynamic", "human", "robot"]


@dataclass(frozen=True)
class Pose2D:
    x: float
    y: float
    yaw: float = 0.0
    """Radians, counter-clockwise from +x."""


@dataclass(frozen=True)
class ConcreteBlock:
    """A floor tile or a wall block filling one cell."""

    name: str
    kind: Literal["floor", "wall"]
    type: ObjectType
    cell: tuple[int, int]
    x: float
    y: float
    size: float
    """Edge length of the square cell (the room's tile size)."""


@dataclass(frozen=True)
class TimedPoint:
    t: float
    x: float
    y: float


@dataclass(frozen=True)
class StartWhen:
    """The trajectory's clock starts when the robot's centre first comes within ``within``
    metres of (x, y), the centre of the floor ``floor``."""

    floor: str
    x: float
    y: float
    within: float


@dataclass(frozen=True)
class TimedTrajectory:
    """Control vertices with their times; for a loop the last point repeats the first."""

    points: tuple[TimedPoint, ...]
    loop: bool
    start_when: StartWhen | None = None
    """None: the times count from the start of the run."""

    @property
    def duration(self) -> float:
        return self.points[-1].t - self.points[0].t


@dataclass(frozen=True)
class ConcreteObject:
    """A static object, dynamic object, human or the robot at its start pose."""

    name: str
    role: Role
    type: ObjectType
    floor: str
    pose: Pose2D
    trajectory: TimedTrajectory | None = None
    behaviour: Behaviour = DEFAULT_BEHAVIOUR
    """How a human reacts to the robot; other roles are always ``scripted``."""


@dataclass(frozen=True)
class ConcreteWorld:
    name: str
    source: str
    tile_size: float
    floors: tuple[ConcreteBlock, ...]
    walls: tuple[ConcreteBlock, ...]
    objects: tuple[ConcreteObject, ...]
    """Everything on floors except the robot, in declaration order."""
    robot: ConcreteObject

    def floor_at(self, x: float, y: float) -> str | None:
        """The inverse mapping: the floor whose tile contains the point, if any."""
        i = math.floor(x / self.tile_size + 0.5)
        j = math.floor(y / self.tile_size + 0.5)
        return self._floor_by_cell().get((i, j))

    def _floor_by_cell(self) -> dict[tuple[int, int], str]:
        cache: dict[tuple[int, int], str] | None = self.__dict__.get("_cells")
        if cache is None:
            cache = {f.cell: f.name for f in self.floors}
            object.__setattr__(self, "_cells", cache)
        return cache

    def floor(self, name: str) -> ConcreteBlock:
        for block in self.floors:
            if block.name == name:
                return block
        raise KeyError(name)

    def bounds(self) -> tuple[float, float, float, float]:
        """(min_x, min_y, max_x, max_y) of all building blocks, in metres."""
        blocks = self.floors + self.walls
        half = self.tile_size / 2
        return (min(b.x for b in blocks) - half, min(b.y for b in blocks) - half,
                max(b.x for b in blocks) + half, max(b.y for b in blocks) + half)

    @property
    def humans(self) -> tuple[ConcreteObject, ...]:
        return tuple(o for o in self.objects if o.role == "human")

    @property
    def animated(self) -> tuple[ConcreteObject, ...]:
        return tuple(o for o in self.objects if o.trajectory is not None)


@dataclass(frozen=True)
class ConcreteGoal:
    name: str
    floor: str
    x: float
    y: float
    yaw: float | None
    """Radians, or None when any heading will do."""
    tolerance: float
    """Metres."""
    timeout: float
    """Seconds."""
    heading_tolerance: float = math.radians(DEFAULT_HEADING_TOLERANCE)
    """Radians the final heading may be off ``yaw``."""


@dataclass(frozen=True)
class ConcreteMission:
    name: str
    source: str
    world: ConcreteWorld
    goals: tuple[ConcreteGoal, ...]
    cycles: int
    time_limit: float
    max_speed: float | None
    sample_rate: float = DEFAULT_SAMPLE_RATE
    """Samples per second of simulation time the data collector takes."""
    data: tuple[str, ...] = COLLECTED_DATA
    """What the data collector forwards (the mission's ``monitor`` block)."""
    faults: tuple[FaultDefinition, ...] = ()
    """The mission's ``fault`` section (rei.runtime.simulation.faults.fault_stage builds the
    stage)."""
    settle: float = 0.0
    """Seconds the mission goes on after its last task ended (the .mission's ``settle``)."""

    def tasks(self) -> tuple[ConcreteGoal, ...]:
        """The goals in the order they are sent (the sequence repeated ``cycles`` times)."""
        return self.goals * self.cycles
