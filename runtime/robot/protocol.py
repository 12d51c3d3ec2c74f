"""The robot under test: the contract a test engineer implements for their navigation software.

A controller is reset with the mission context (the known static map, the robot's footprint,
drive limits and laser), then called at the control rate with an ``Observation`` (what the
robot's own sensors say: odometry and the latest laser scan, never the ground truth) and
answers a ``VelocityCommand``. Navigation goals go through the action state machine of thesis
Figure 22 (the ROS actionlib states): ``send_goal`` makes a goal PENDING, the controller makes
it ACTIVE and ends it SUCCEEDED or ABORTED; ``cancel_goal`` (or a new goal) ends it PREEMPTED.
``GoalTracker`` implements those transitions so a controller cannot make an illegal one.
This module must never import pybullet.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

from rei.catalogue import DriveSpec, LaserSpec
from rei.runtime.messages import LaserScan, NavState


@dataclass(frozen=True)
class VelocityCommand:
    """A differential-drive command: forward m/s and counter-clockwise rad/s."""

    linear: float
    angular: float

    @property
    def finite(self) -> bool:
        return math.isfinite(self.linear) and math.isfinite(self.angular)


STOP = VelocityCommand(0.0, 0.0)


@dataclass(frozen=True)
class NavGoal:
    name: str
    x: float
    y: float
    yaw: float | None
    """Radians, or None when any heading will do."""
    tolerance: float
    """Metres: how close the robot must end to (x, y)."""
    timeout: float


@dataclass(frozen=True)
class GoalFeedback:
    state: NavState
    goal: str | None
    distance_remaining: float | None = None
    message: str = ""
    """Why a goal was aborted, or what the controller is doing."""


@dataclass(frozen=True)
class MapObstacle:
    """An obstacle of the known static map: a box (size_x, size_y) or a cylinder (radius)."""

    name: str
    role: str
    x: float
    y: float
    yaw: float
    shape: str
    size_x: float = 0.0
    size_y: float = 0.0
    radius: float = 0.0


@dataclass(frozen=True)
class ControllerContext:
    """What the robot knows before the mission starts."""

    robot_size: tuple[float, float]
    """Footprint box (along x, along y) in the robot's frame."""
    drive: DriveSpec
    laser: LaserSpec
    start_pose: tuple[float, float, float]
    obstacles: tuple[MapObstacle, ...]
    """The static map: wall tiles and static objects (never humans or dynamic objects)."""
    bounds: tuple[float, float, float, float]
    tile_size: float
    control_rate: float
    seed: int
    max_speed: float | None = None
    """The mission's speed limit, if any (m/s)."""


@dataclass(frozen=True)
class Observation:
    time: float
    odom_pose: tuple[float, float, float]
    odom_twist: tuple[float, float]
    scan: LaserScan | None
    """The latest scan (None before the first)."""
    scan_time: float | None = field(default=None)


@runtime_checkable
class Controller(Protocol):
    """The robot's navigation software as REI drives it."""

    name: str

    def reset(self, context: ControllerContext) -> None: ...

    def send_goal(self, goal: NavGoal) -> None: ...

    def cancel_goal(self) -> None: ...

    def feedback(self) -> GoalFeedback: ...

    def step(self, observation: Observation) -> VelocityCommand: ...


class IllegalTransition(RuntimeError):
    """A controller tried a goal state change Figure 22 does not allow."""


_ALLOWED: dict[NavState, frozenset[NavState]] = {
    NavState.IDLE: frozenset({NavState.PENDING}),
    NavState.PENDING: frozenset({NavState.ACTIVE, NavState.ABORTED, NavState.PREEMPTED}),
    NavState.ACTIVE: frozenset({NavState.SUCCEEDED, NavState.ABORTED, NavState.PREEMPTED}),
    NavState.SUCCEEDED: frozenset({NavState.PENDING}),
    NavState.ABORTED: frozenset({NavState.PENDING}),
    NavState.PREEMPTED: frozenset({NavState.PENDING}),
}
TERMINAL = frozenset({NavState.SUCCEEDED, NavState.ABORTED, NavState.PREEMPTED})


def legal_transition(old: NavState, new: NavState) -> bool:
    return new == old or new in _ALLOWED[old]


def observable_transition(old: NavState, new: NavState) -> bool:
    """Whether ``new`` may be seen one call after ``old`` (pending may pass through active)."""
    return legal_transition(old, new) or (
        old == NavState.PENDING and new in _ALLOWED[NavState.ACTIVE])


class GoalTracker:
    """The goal state machine of Figure 22, for controllers to hold their goal in."""

    def __init__(self) -> None:
        self.state = NavState.IDLE
        self.goal: NavGoal | None = None
        self.message = ""

    def send(self, goal: NavGoal) -> None:
        if self.state in (NavState.PENDING, NavState.ACTIVE):
            self.state = NavState.PREEMPTED
        self.goal, self.state, self.message = goal, NavState.PENDING, ""

    def _move(self, new: NavState, message: str = "") -> None:
        if not legal_transition(self.state, new):
            raise IllegalTransition(f"goal state {self.state.value} -> {new.value}")
        self.state, self.message = new, message

    def accept(self) -> None:
        self._move(NavState.ACTIVE)

    def succeed(self, message: str = "") -> None:
        self._move(NavState.SUCCEEDED, message)

    def abort(self, message: str) -> None:
        self._move(NavState.ABORTED, message)

    def cancel(self) -> None:
        if self.state in (NavState.PENDING, NavState.ACTIVE):
            self._move(NavState.PREEMPTED, "cancelled")

    @property
    def running(self) -> bool:
        return self.state in (NavState.PENDING, NavState.ACTIVE)

    def feedback(self, distance: float | None = None) -> GoalFeedback:
        return GoalFeedback(self.state, self.goal.name if self.goal else None, distance,
                            self.message)
