"""The shared message types of a run: the typed, versioned sample stream (thesis 5.1.4, 9.1).

The data collector produces a ``StreamHeader`` once and then one ``Sample`` per collection
tick; the event automata and the evaluator consume them, live or replayed from a trace.
Per-object state travels as numpy arrays aligned with ``StreamHeader.objects`` so the monitor
can compute geometry for thousands of objects vectorised.

A contract at runtime's root, with ``ros`` (REI's one ROS 2 mapping) and ``sink`` (the
``SampleSink`` protocol the stream is published to): it may import only the languages' models,
the catalogue and numpy (rosbags in ``ros``), and must never import pybullet or any wing.
"""

from __future__ import annotations

import math
from dataclasses import MISSING, dataclass, field, fields, replace
from enum import StrEnum
from typing import Any, ClassVar, Literal, get_args, get_origin, get_type_hints

import numpy as np

from rei.catalogue import Footprint
from rei.lang.mission.model import COLLECTED_DATA

SCHEMA_VERSION = 4
"""Bumped whenever a field changes meaning; readers refuse older versions unless they say
otherwise (2: the header carries the laser's mount point; 3: the header carries the
mission's facts, a sample the bodies touched since the previous one and the robot's raw
velocity command, a failed task its cause; 4: the header names the collected data, and a
sample carries only those)."""


class NavState(StrEnum):
    """The navigation action's state (thesis Figure 22, the ROS actionlib states)."""

    IDLE = "idle"
    PENDING = "pending"
    ACTIVE = "active"
    SUCCEEDED = "succeeded"
    ABORTED = "aborted"
    PREEMPTED = "preempted"


MissionEventKind = Literal["begin", "task_start", "task_success", "task_fail", "end"]
MISSION_EVENT_KINDS: tuple[str, ...] = get_args(MissionEventKind)
TASK_EVENT_KINDS = ("task_start", "task_success", "task_fail")
"""The kinds that belong to one task: they name it (``task``) and its position (``index``);
``begin`` and ``end`` name neither."""

FAILURE_CAUSES = ("aborted", "preempted", "timeout", "position", "heading", "abandoned", "cut")
"""The machine-readable causes of a ``task_fail`` event: the controller aborted or preempted
the goal, the goal outlived its timeout, the controller claimed success outside the position
tolerance or with the wrong heading, the mission ended early (its time limit, a run error,
an interruption) while the task ran, or the run was cut short by the user's ``--duration``
(the task's end was never observed). Requirements select on these, never on the reason
text."""


@dataclass(frozen=True)
class MissionEvent:
    """Something the mission executor did (thesis 6.1.4): SIG_MISSION_* come from these."""

    kind: MissionEventKind
    time: float
    task: str | None = None
    """The goal's name, for task events."""
    index: int | None = None
    """Position of the task in the sent sequence (cycles expanded), from 0."""
    reason: str = ""
    """Why a task failed, for people: 'aborted: blocked', 'timeout after 30 s', ..."""
    cause: str = ""
    """Why a task failed, for requirements: one of FAILURE_CAUSES on ``task_fail``, else ''."""


ObjectRole = Literal["wall", "static", "dynamic", "human", "robot"]
OBJECT_ROLES: tuple[str, ...] = get_args(ObjectRole)


@dataclass(frozen=True)
class ObservedObject:
    """A body the monitor watches, with what the geometry queries need about it."""

    name: str
    role: ObjectRole
    type: str
    footprint: Footprint
    """In the object's own frame; walls carry a Box of the tile size."""
    height: float


@dataclass(frozen=True)
class GoalFacts:
    """One goal of the mission as the executor judges it (world frame, metres, radians)."""

    name: str
    x: float
    y: float
    heading: float | None
    """Radians, world frame; None when any heading will do."""
    tolerance: float
    """Metres from (x, y) within which a claimed success counts."""
    heading_tolerance: float
    """Radians the final heading may differ from ``heading`` (unused without a heading)."""
    timeout: float
    """Seconds the task may run before it is cancelled."""


@dataclass(frozen=True)
class MissionFacts:
    """What the mission asks for, so requirements can name goals, limits and tolerances
    without re-reading the .mission file (a replayed trace carries them with it)."""

    goals: tuple[GoalFacts, ...]
    """As declared: one cycle; the tasks are this sequence repeated ``cycles`` times."""
    cycles: int
    time_limit: float
    """Seconds of simulated time the whole mission may take."""
    speed_limit: float
    """m/s the robot can actually reach: min(drive max_linear, mission max_speed)."""
    turn_limit: float
    """rad/s: the drive's max_angular."""
    mission_max_speed: float | None
    """The mission's own max_speed (m/s), None when it sets none."""


@dataclass(frozen=True)
class StreamHeader:
    version: int
    world: str
    mission: str
    seed: int
    rate: float
    """Samples per second of simulation time."""
    robot: ObservedObject
    objects: tuple[ObservedObject, ...]
    tile_size: float
    floors: tuple[tuple[str, float, float], ...] = ()
    """(name, x, y) of every floor centre: the abstract model's inverse mapping."""
    laser_mount: tuple[float, float] = (0.0, 0.0)
    """(x, y) of the laser in the robot's frame, metres; its beams point along the robot's
    heading plus the scan's angles. The monitor measures laser clearance from here to the
    robot footprint's boundary (issue 6: the TurtleBot3 Waffle's laser sits 6.4 cm back)."""
    mission_facts: MissionFacts | None = None
    """The goals and limits of the mission run; None for streams not made by a mission run."""
    data: tuple[str, ...] = COLLECTED_DATA
    """What the data collector forwards (thesis 6.1.2), in COLLECTED_DATA's order: the
    samples carry these and nothing of the others (see ``BELIEF_DATA``)."""
    faults: tuple[tuple[str, str], ...] = ()
    """(name, entry as written) of every fault injected between the sensors and the robot
    under test (``rei.runtime.simulation.faults``), in declaration order; empty for a run
    without."""


@dataclass(frozen=True)
class LaserScan:
    angle_min: float
    angle_increment: float
    range_min: float
    range_max: float
    ranges: np.ndarray = field(compare=False)
    """float64 array, one range per beam; max_range where nothing was hit."""


@dataclass(frozen=True)
class RobotBelief:
    """What the robot believes (thesis 5.1.5.1 robot description model)."""

    odom: tuple[float, float, float]
    """(x, y, yaw) from odometry, possibly drifted."""
    odom_twist: tuple[float, float]
    """(linear, angular) velocity from odometry."""
    laser_min: float
    """Minimum of the latest scan's ranges (max_range when it saw nothing)."""
    scan: LaserScan | None
    nav_state: NavState
    task: str | None
    """Name of the goal being executed, if any."""
    cmd: tuple[float, float] = (0.0, 0.0)
    """(linear m/s, angular rad/s) the controller last returned, before the motor model
    clipped it to the drive limits: requirements on what the software *asked* for (a
    controller commanding 2 m/s to a 0.26 m/s drive) cannot be read from the motion."""


BELIEF_DATA: dict[str, tuple[str, ...]] = {
    "odometry": ("odom", "odom_twist"),
    "laser": ("laser_min", "scan"),
    "nav_state": ("nav_state", "task", "cmd"),
}
"""The fields of ``RobotBelief`` each kind of collected data fills. A stream that does not
collect a kind carries ``UNCOLLECTED``'s values there (the trace omits them): no consumer may
read them, and the monitor refuses a specification that would (``rei.runtime.
observation.monitor.needs``). Ground truth (the poses, velocities and contacts) is always collected;
``mission_events`` fills ``Sample.events``."""

UNCOLLECTED = RobotBelief((0.0, 0.0, 0.0), (0.0, 0.0), 0.0, None, NavState.IDLE, None,
                          (0.0, 0.0))
"""The belief of a stream that collects none of BELIEF_DATA."""


def collected_belief(belief: RobotBelief, data: tuple[str, ...]) -> RobotBelief:
    """``belief`` with the fields of the data not in ``data`` set to ``UNCOLLECTED``'s."""
    dropped = {key: getattr(UNCOLLECTED, key) for kind, keys in BELIEF_DATA.items()
               if kind not in data for key in keys}
    return replace(belief, **dropped) if dropped else belief


@dataclass(frozen=True, eq=False)
class Sample:
    """One observation of the whole run at simulation time ``time``."""

    seq: int
    """0, 1, 2, ... per run; a gap means a lost sample."""
    time: float
    """Simulation time in seconds."""
    robot_pose: tuple[float, float, float]
    """Ground truth (x, y, yaw)."""
    robot_twist: tuple[float, float, float]
    """Ground truth (vx, vy, wz) in the world frame."""
    poses: np.ndarray
    """(N, 3) float64 ground-truth (x, y, yaw) of StreamHeader.objects, in that order."""
    twists: np.ndarray
    """(N, 3) float64 ground-truth (vx, vy, wz)."""
    belief: RobotBelief
    events: tuple[MissionEvent, ...] = ()
    """Mission events since the previous sample."""
    contacts: tuple[int, ...] = ()
    """Sorted indices into StreamHeader.objects of the bodies the robot physically touched
    at any physics step since the previous sample (this one included). Physics runs faster
    than the samples, so a brief touch between two samples would otherwise be lost while the
    sampled footprint distance never drops below the collision threshold."""
    faults: tuple[str, ...] = ()
    """Names of the header's faults active when the sample was taken, in the header's order:
    which lie the robot was told, so every signal can be read against it (events.csv)."""


# ---- the run loop's messages ----------------------------------------------------------------
#
# The components of a run (``rei.runtime.simulation.loop``) talk only through these. Each is
# stamped with
# the simulation time it describes and a sequence number per topic (0, 1, 2, ... per run: a
# gap means a lost message), and round-trips through JSON (``to_json``/``message_from_json``)
# so a bus can carry it between processes. They are built at most once per physics step and
# hold what their producer already had (tuples, numpy arrays): nothing is copied to send them.

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
