"""The robot under test: the contract a test engineer implements for their navigation software.

A controller is reset with the mission context (the known static map, the robot's footprint,
drive limits and laser), then called at the control rate with an ``Observation`` (what the
robot's own sensors say: odometry and the latest laser scan, never the ground truth) and
answers a ``VelocityCommand``. Navigation goals go through the action state machine of thesis
Figure 22 (the ROS actionlib states): ``send_goal`` makes a goal PENDING, the controller makes
it ACTIVE and ends it SUCCEEDED or ABORTED; ``cancel_goal`` (or a new goal) ends it PREEMPTED.
``GoalTracker`` implements those transitions so a controller cannot make an illegal one.

What a controller answers is checked at the boundary (``checked_command``,
``checked_feedback``): the run never lets a string, a complex number, an array or an int
beyond float range travel into the physics, the trace or the monitor, where it would surface
as a traceback far from its cause. What it is handed is read-only (``read_only_scan``): a
controller cannot change what the sensors measured. This module must never import pybullet.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field, replace
from typing import Any, Protocol, runtime_checkable

import numpy as np

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
    """The robot's navigation software as REI drives it.

    ``feedback()`` must not change the controller's state: it answers a pure function of
    what ``reset``, ``send_goal``, ``cancel_goal`` and ``step`` made of the controller. REI
    relies on it to ask once per state: the run computes the feedback right after each
    ``step`` and ``send_goal`` and answers every ``feedback()`` until the next of those
    calls from it (one round trip to the robot's process per control tick), so a
    controller that counts or otherwise reacts to its feedback calls sees fewer of them.
    """

    name: str

    def reset(self, context: ControllerContext) -> None: ...

    def send_goal(self, goal: NavGoal) -> None: ...

    def cancel_goal(self) -> None: ...

    def feedback(self) -> GoalFeedback:
        """The goal's state; a pure function of the controller's state (changes nothing)."""
        ...

    def step(self, observation: Observation) -> VelocityCommand: ...


class ContractViolation(ValueError):
    """A controller's answer is not what the contract promises; ``str()`` is the reason,
    naming the field, what was expected and what was found."""

    def __init__(self, reason: str, non_finite: bool = False) -> None:
        super().__init__(reason)
        self.non_finite = non_finite
        """The value was a real number, but NaN or infinite (a numeric fault, not a type one)."""


def _shown(value: Any) -> str:
    """A value as an error message shows it: its type and a short repr."""
    if isinstance(value, np.ndarray):
        return f"numpy array of shape {value.shape}"
    if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > 64:
        # repr of a huge int is slow, long, or refused (more than 4300 digits)
        return f"int of about {int(value.bit_length() * math.log10(2)) + 1} digits"
    try:
        text = repr(value)
    except Exception:  # noqa: BLE001  (a user's object whose repr breaks)
        text = "<unprintable>"
    if len(text) > 40:
        text = text[:37] + "..."
    return f"{type(value).__name__} {text}"


def real_number(value: Any, where: str) -> float:
    """``value`` as a finite float; ContractViolation unless it is a finite real number.

    Python and numpy integers and floats are real numbers; bool is not (``True`` as a speed
    is a bug, not 1 m/s), nor are complex numbers, strings, None or arrays (even of one
    element: a controller that sends ``np.array([0.1])`` has a shape bug worth seeing).
    """
    if isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Real) \
            or isinstance(value, np.ndarray):
        raise ContractViolation(f"{where}: expected a finite real number, found {_shown(value)}")
    try:
        number = float(value)
    except (OverflowError, ValueError, TypeError):
        raise ContractViolation(f"{where}: expected a finite real number, found "
                                f"{_shown(value)} (beyond float range)") from None
    if not math.isfinite(number):
        raise ContractViolation(f"{where}: expected a finite real number, found {number}",
                                non_finite=True)
    return number


def checked_command(value: Any) -> VelocityCommand:
    """A plain ``VelocityCommand`` of two finite floats, or ContractViolation saying why not."""
    if not isinstance(value, VelocityCommand):
        raise ContractViolation(f"command: expected a VelocityCommand, found {_shown(value)}")
    return VelocityCommand(real_number(value.linear, "command.linear"),
                           real_number(value.angular, "command.angular"))


def _is_text(value: Any) -> bool:
    """A string that can be written to a log, a trace and a terminal: a lone surrogate
    ('\\ud800') cannot, and used to end the run as an internal error of REI."""
    if not isinstance(value, str):
        return False
    try:
        value.encode("utf-8")
    except UnicodeEncodeError:
        return False
    return True


def checked_feedback(value: Any) -> GoalFeedback:
    """A plain ``GoalFeedback`` with fields of the promised types, or ContractViolation."""
    if not isinstance(value, GoalFeedback):
        raise ContractViolation(f"feedback: expected a GoalFeedback, found {_shown(value)}")
    if not isinstance(value.state, NavState):
        raise ContractViolation(f"feedback.state: expected a NavState, found "
                                f"{_shown(value.state)}")
    if value.goal is not None and not _is_text(value.goal):
        raise ContractViolation(f"feedback.goal: expected a goal name or None, found "
                                f"{_shown(value.goal)}")
    distance = value.distance_remaining
    if distance is not None:
        # inf is an honest answer (no path known); NaN and negative distances are not
        try:
            distance = real_number(distance, "feedback.distance_remaining")
        except ContractViolation as problem:
            if not (problem.non_finite and distance == math.inf):
                raise
            distance = math.inf
        if distance < 0:
            raise ContractViolation(f"feedback.distance_remaining: expected metres >= 0, inf "
                                    f"or None, found {distance}")
    if not _is_text(value.message):
        raise ContractViolation(f"feedback.message: expected a string of text, found "
                                f"{_shown(value.message)}")
    return GoalFeedback(NavState(value.state), None if value.goal is None else str(value.goal),
                        distance, str(value.message))


def read_only_scan(scan: LaserScan | None) -> LaserScan | None:
    """The controller's copy of a scan: its own ranges, read-only (writing raises), so the
    sensor's array that the trace and the monitor record stays what was measured."""
    if scan is None:
        return None
    ranges = np.array(scan.ranges, dtype=float)
    ranges.flags.writeable = False
    # A view of a read-only array cannot be made writeable again (its owner could).
    return replace(scan, ranges=ranges.view())


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
