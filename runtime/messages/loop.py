"""The run loop's messages: what the components of a run exchange, and their JSON form.

The components of a run (``rei.runtime.simulation.loop``) talk only through these. Each is
stamped with the simulation time it describes and a sequence number per topic (0, 1, 2, ...
per run: a gap means a lost message), and round-trips through JSON (``to_json``/
``message_from_json``) so a bus can carry it between processes. They are built at most once
per physics step and hold what their producer already had (tuples, numpy arrays): nothing is
copied to send them.

This module must never import pybullet, the monitor or any wing.
"""

from __future__ import annotations

import math
from dataclasses import MISSING, dataclass, fields
from typing import Any, ClassVar, get_args, get_origin, get_type_hints

import numpy as np

from rei.runtime.messages.stream import MISSION_EVENT_KINDS, LaserScan, MissionEvent, NavState

Pose = tuple[float, float, float]
Velocity = tuple[float, float]


@dataclass(frozen=True, slots=True)
class RobotTruth:
    """The robot's ground-truth pose and the bodies it touches, every physics step."""

    TOPIC: ClassVar[str] = "truth/robot"
    seq: int
    time: float
    pose: Pose
    contacts: tuple[int, ...] = ()
    """Sorted indices into ``StreamHeader.objects`` of the bodies touching the robot now."""


@dataclass(frozen=True, slots=True, eq=False)
class BodyStates:
    """Ground truth of the robot's velocity and of every object, when a reader needs it."""

    TOPIC: ClassVar[str] = "truth/bodies"
    seq: int
    time: float
    robot_twist: tuple[float, float, float]
    """World-frame (vx, vy, wz)."""
    poses: np.ndarray
    """(N, 3) (x, y, yaw) of the world's objects (walls excluded), in declaration order."""
    twists: np.ndarray
    """(N, 3) (vx, vy, wz), aligned with ``poses``."""
    touched: tuple[int, ...] = ()
    """Sorted indices into ``StreamHeader.objects`` of every body the robot touched at any
    physics step since the previous sample's ``BodyStates`` (empty in the others)."""


@dataclass(frozen=True, slots=True)
class TrackedBodies:
    """What the animator steers by, every control tick: its bodies' poses and the robot's."""

    TOPIC: ClassVar[str] = "truth/animated"
    seq: int
    time: float
    poses: tuple[Pose, ...]
    """In the animator's body order."""
    robot_pose: Pose
    robot_twist: tuple[float, float, float]


@dataclass(frozen=True, slots=True)
class BodyVelocities:
    """Planar velocities the animator sets on its bodies for the physics steps from the one
    at ``time`` on: ``steps[j]`` is for the step ``j`` steps later (one control period)."""

    TOPIC: ClassVar[str] = "animator/velocities"
    seq: int
    time: float
    steps: tuple[tuple[tuple[int, float, float, float], ...], ...]
    """Per step, (pybullet body id, vx, vy, wz) per animated body."""


@dataclass(frozen=True, slots=True, eq=False)
class ScanReading:
    """A scan the laser measured at ``time``."""

    TOPIC: ClassVar[str] = "sensor/laser"
    seq: int
    time: float
    scan: LaserScan


@dataclass(frozen=True, slots=True)
class OdometryReading:
    """What the odometry sensor measured at ``time`` (possibly drifted)."""

    TOPIC: ClassVar[str] = "sensor/odometry"
    seq: int
    time: float
    pose: Pose
    twist: Velocity


@dataclass(frozen=True, slots=True, eq=False)
class RobotView:
    """What the robot under test receives at ``time``: the sensors as the fault stage passes
    them (the same objects when no fault is active). The collector records it as the belief."""

    TOPIC: ClassVar[str] = "robot/view"
    seq: int
    time: float
    scan: LaserScan | None
    scan_time: float | None
    odom: Pose
    odom_twist: Velocity


@dataclass(frozen=True, slots=True)
class CommandIssued:
    """The robot under test's answer at ``time``: what it asked for (``raw``) and what
    reaches the motors (``motor``: through the fault stage, clipped to the drive limits)."""

    TOPIC: ClassVar[str] = "robot/command"
    seq: int
    time: float
    raw: Velocity
    motor: Velocity


@dataclass(frozen=True, slots=True)
class MissionStatus:
    """The mission executor's tick: the events it emitted and the navigation state."""

    TOPIC: ClassVar[str] = "mission/status"
    seq: int
    time: float
    events: tuple[MissionEvent, ...]
    nav_state: NavState
    task: str | None


@dataclass(frozen=True, slots=True)
class SignalFired:
    """A ``.vepl`` signal the monitor fired at ``time``."""

    TOPIC: ClassVar[str] = "monitor/signal"
    seq: int
    time: float
    name: str


LoopMessage = (RobotTruth | BodyStates | TrackedBodies | BodyVelocities | ScanReading
               | OdometryReading | RobotView | CommandIssued | MissionStatus | SignalFired)
LOOP_MESSAGES: dict[str, type[LoopMessage]] = {
    m.TOPIC: m for m in (RobotTruth, BodyStates, TrackedBodies, BodyVelocities, ScanReading,
                         OdometryReading, RobotView, CommandIssued, MissionStatus, SignalFired)}
"""Topic name -> message class."""


def message_to_json(message: LoopMessage) -> dict[str, Any]:
    """The message as JSON-ready data: ``{"topic": ..., "seq": ..., "time": ..., ...}``."""
    out: dict[str, Any] = {"topic": message.TOPIC}
    for f in fields(message):
        out[f.name] = _encode(getattr(message, f.name))
    return out


def message_from_json(data: Any) -> LoopMessage:
    """The message ``message_to_json`` made; ``MessageError`` naming the topic and field
    when ``data`` is not one."""
    if not isinstance(data, dict):
        raise MessageError(f"a message expected to be a JSON object, found {type(data).__name__}")
    topic = data.get("topic")
    cls = LOOP_MESSAGES.get(topic) if isinstance(topic, str) else None
    if cls is None:
        raise MessageError(f"a message's topic expected to be one of "
                           f"{', '.join(sorted(LOOP_MESSAGES))}, found {topic!r}")
    values: dict[str, Any] = {}
    hints = get_type_hints(cls)
    for f in fields(cls):
        if f.name not in data:
            if f.default is MISSING:
                raise MessageError(f"{topic}: field '{f.name}' expected, found none")
            continue
        try:
            values[f.name] = _decode(hints[f.name], data[f.name])
        except (TypeError, ValueError, KeyError) as exc:
            raise MessageError(f"{topic}: field '{f.name}': {exc}") from None
    return cls(**values)


class MessageError(ValueError):
    """A message that is not one of the loop's (bad JSON from a bus or a file)."""


def _encode(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, LaserScan):
        return {"angle_min": value.angle_min, "angle_increment": value.angle_increment,
                "range_min": value.range_min, "range_max": value.range_max,
                "ranges": value.ranges.tolist()}
    if isinstance(value, MissionEvent):
        return {f.name: getattr(value, f.name) for f in fields(value)}
    if isinstance(value, NavState):
        return value.value
    if isinstance(value, tuple):
        return [_encode(v) for v in value]
    return value


def _number(value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise TypeError(f"expected a number, found {value!r}")
    number = float(value)
    if not math.isfinite(number):
        raise ValueError(f"expected a finite number, found {value!r}")
    return number


def _decode(hint: Any, value: Any) -> Any:  # noqa: PLR0911  (one branch per type)
    if hint is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise TypeError(f"expected an integer, found {value!r}")
        return value
    if hint is float:
        return _number(value)
    if hint is str:
        if not isinstance(value, str):
            raise TypeError(f"expected a string, found {value!r}")
        return value
    if hint is np.ndarray:
        array = np.array(value, dtype=float).reshape(-1, 3)
        if not np.isfinite(array).all():
            raise ValueError("expected finite numbers")
        return array
    if hint is LaserScan:
        if not isinstance(value, dict):
            raise TypeError(f"expected a scan object, found {value!r}")
        ranges = np.array(value["ranges"], dtype=float)
        if ranges.ndim != 1 or not np.isfinite(ranges).all():
            raise ValueError("expected a list of finite ranges")
        ranges.flags.writeable = False
        return LaserScan(_number(value["angle_min"]), _number(value["angle_increment"]),
                         _number(value["range_min"]), _number(value["range_max"]), ranges)
    if hint is MissionEvent:
        if not isinstance(value, dict):
            raise TypeError(f"expected a mission event object, found {value!r}")
        if value.get("kind") not in MISSION_EVENT_KINDS:
            raise ValueError(f"expected a mission event kind, found {value.get('kind')!r}")
        task, index = value.get("task"), value.get("index")
        reason, cause = value.get("reason", ""), value.get("cause", "")
        if task is not None and not isinstance(task, str) or not isinstance(reason, str) \
                or not isinstance(cause, str):
            raise TypeError("expected a mission event's task, reason and cause as strings")
        if index is not None and (isinstance(index, bool) or not isinstance(index, int)):
            raise TypeError(f"expected a mission event's index as an integer, found {index!r}")
        return MissionEvent(value["kind"], _number(value["time"]), task, index, reason, cause)
    if hint is NavState:
        return NavState(value)
    args = get_args(hint)
    if type(None) in args:  # X | None
        inner = next(a for a in args if a is not type(None))
        return None if value is None else _decode(inner, value)
    if get_origin(hint) is tuple:
        if not isinstance(value, list):
            raise TypeError(f"expected a list, found {value!r}")
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_decode(args[0], v) for v in value)
        if len(value) != len(args):
            raise ValueError(f"expected {len(args)} values, found {len(value)}")
        return tuple(_decode(a, v) for a, v in zip(args, value, strict=True))
    raise TypeError(f"cannot decode {hint!r}")
