"""The sample stream of a run: its typed, versioned records (thesis 5.1.4, 9.1).

The data collector produces a ``StreamHeader`` once and then one ``Sample`` per collection
tick; the event automata and the evaluator consume them, live or replayed from a trace.
Per-object state travels as numpy arrays aligned with ``StreamHeader.objects`` so the monitor
can compute geometry for thousands of objects vectorised.

The mission's events and facts, the observed objects, the robot's belief and the header and
samples that carry them. It may import only the languages' models, the catalogue and numpy,
and must never import pybullet, the monitor or any wing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from enum import StrEnum
from typing import Literal, get_args

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
    accel_limit: float = math.inf
    decel_limit: float = math.inf
    """m/s^2 the linear command may rise and fall by per second: the drive's
    max_linear_accel and max_linear_decel (inf: not known, a trace recorded before REI
    carried them)."""
    turn_accel_limit: float = math.inf
    turn_decel_limit: float = math.inf
    """rad/s^2, likewise for the angular command (max_angular_accel, max_angular_decel)."""


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
