"""REI's one ROS 2 mapping: topics, frames, message types, and conversions both ways.

REI -> ROS (``RosViews``): the sample stream as messages of the standard ROS 2 types,
CDR-encoded, for recordings (and for the bus's ROS 2 profile and the Foxglove view, which
use these names read-only). ROS -> REI (``pose_of``, ``scan_of``, ``odometry_of``,
``command_of``, ``seconds``, ``NAV2_STATUS``): decoded ROS 2 messages (rosbags' or any
object with the same fields) back into REI's values, for judging ROS 2 recordings REI did
not make (``rei.runtime.observation.recordings.foreign``).

Built with rosbags' type store of ROS 2 Humble (no ROS installation needed); each topic's
schema is the type's ``ros2msg`` definition with its dependencies, as `ros2 bag` records
it, so Foxglove and ROS 2 tools decode the recording. These views lose precision (ranges
are float32, yaw becomes a quaternion): the exact record is the /rei/trace channel.

Frames: ``map`` is the world; each body (the robot and every observed object) has the
frame of its name, placed by /tf with its ground-truth pose; the laser is the robot's frame
``ROBOT/laser`` at the laser's mount (/tf_static). The world's markers hang on the bodies'
frames (``frame_locked``), so moving bodies carry their markers. This module must never
import pybullet. It stays one module (a little over 450 lines) on purpose: both directions of
the one mapping side by side, so a topic, frame or type cannot change in one and not the other.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import asdict
from typing import Any

import numpy as np
from rosbags.typesys import Stores, get_typestore

from rei.catalogue import Box, Cylinder, Footprint, Polygon
from rei.runtime.messages import (
    LaserScan,
    MissionEvent,
    NavState,
    ObservedObject,
    Sample,
    StreamHeader,
)

STORE = Stores.ROS2_HUMBLE

SCAN = "sensor_msgs/msg/LaserScan"
ODOMETRY = "nav_msgs/msg/Odometry"
TWIST = "geometry_msgs/msg/Twist"
TF = "tf2_msgs/msg/TFMessage"
MARKERS = "visualization_msgs/msg/MarkerArray"
TEXT = "std_msgs/msg/String"

NAV2_ACTION = "/navigate_to_pose/_action"
"""Nav2's navigate_to_pose action as ROS 2 topics: ``/status`` (action_msgs/msg/
GoalStatusArray) and ``/feedback`` (its FeedbackMessage), recorded with
``--include-hidden-topics``."""
NAV2_STATUS_TOPIC = f"{NAV2_ACTION}/status"
GOAL_STATUS = "action_msgs/msg/GoalStatusArray"
CLOCK = "rosgraph_msgs/msg/Clock"

TOPICS: dict[str, str] = {
    "/scan": SCAN,
    "/odom": ODOMETRY,
    "/cmd_vel": TWIST,
    "/tf": TF,
    "/tf_static": TF,
    "/world/markers": MARKERS,
    "/rei/events": TEXT,
    "/rei/signals": TEXT,
    NAV2_STATUS_TOPIC: GOAL_STATUS,
}
"""Every ROS 2 topic of a recording and its message type."""

ROBOT_TOPICS: dict[str, str] = {
    "/tf": TF,
    "/tf_static": TF,
    "/odom": ODOMETRY,
    "/scan": SCAN,
    "/cmd_vel": TWIST,
    "/clock": CLOCK,
    NAV2_STATUS_TOPIC: GOAL_STATUS,
}
"""The topics REI reads from a ROS 2 robot's recording (a Gazebo run or a real robot) and
their types: ground truth on /tf, the robot's belief on /odom, /scan and /cmd_vel, the time
on /clock (else the stamps), mission progress from Nav2's action status when present."""

BELIEF_TOPICS: dict[str, str] = {"odometry": "/odom", "laser": "/scan", "nav_state": "/cmd_vel"}
"""The topic carrying each kind of collected belief data (``messages.BELIEF_DATA``)."""

LATCHED = ("/tf_static", "/world/markers")
"""Topics written once at the start: recorded with a transient-local QoS, as ROS latches."""

MAP = "map"

# visualization_msgs/msg/Marker's constants (type, action)
CUBE, CYLINDER, LINE_STRIP, CUBE_LIST, ADD = 1, 3, 4, 6, 0

_ROLE_COLOURS: dict[str, tuple[float, float, float, float]] = {
    "wall": (0.55, 0.55, 0.6, 1.0),
    "static": (0.6, 0.45, 0.3, 1.0),
    "dynamic": (0.9, 0.6, 0.1, 1.0),
    "human": (0.9, 0.25, 0.25, 1.0),
    "robot": (0.2, 0.45, 0.9, 1.0),
}
_FLOOR_COLOUR = (0.85, 0.85, 0.8, 1.0)
_FLAT = 0.01
"""Height (m) of a marker of a flat thing: a floor tile, a body of height 0."""


def laser_frame(header: StreamHeader) -> str:
    return f"{header.robot.name}/laser"


class RosViews:
    """Serialises one stream's ROS 2 messages (one instance per recording)."""

    def __init__(self) -> None:
        self.store = get_typestore(STORE)
        t = self.store.types
        self._time = t["builtin_interfaces/msg/Time"]
        self._header = t["std_msgs/msg/Header"]
        self._vector = t["geometry_msgs/msg/Vector3"]
        self._point = t["geometry_msgs/msg/Point"]
        self._quaternion = t["geometry_msgs/msg/Quaternion"]
        self._pose = t["geometry_msgs/msg/Pose"]
        self._pose_cov = t["geometry_msgs/msg/PoseWithCovariance"]
        self._twist = t["geometry_msgs/msg/Twist"]
        self._twist_cov = t["geometry_msgs/msg/TwistWithCovariance"]
        self._transform = t["geometry_msgs/msg/Transform"]
        self._transform_stamped = t["geometry_msgs/msg/TransformStamped"]
        self._tf = t[TF]
        self._scan = t[SCAN]
        self._odometry = t[ODOMETRY]
        self._string = t[TEXT]
        self._marker = t["visualization_msgs/msg/Marker"]
        self._markers = t[MARKERS]
        self._colour = t["std_msgs/msg/ColorRGBA"]
        self._duration = t["builtin_interfaces/msg/Duration"]
        self._covariance = np.zeros(36, dtype=np.float64)
        self._identity = self._quat(0.0)
        # Set-up work done here, before the run: the schemas, and rosbags' serialisers of
        # every type (generated and compiled on first use) -- not in the run's first sample.
        self._schemas = {t: self.store.generate_msgdef(t, ros_version=2)[0].encode("utf-8")
                         for t in set(TOPICS.values())}
        for msgtype in self._schemas:
            self.store.get_msgdef(msgtype)

    def schema(self, msgtype: str) -> bytes:
        """The type's ``ros2msg`` definition with its dependencies (`ros2 bag`'s form)."""
        return self._schemas[msgtype]

    def _cdr(self, message: Any, msgtype: str) -> bytes:
        return bytes(self.store.serialize_cdr(message, msgtype))

    # ---- pieces ---------------------------------------------------------------------------

    def _stamp(self, time: float, frame: str) -> Any:
        ns = stamp_ns(time)
        return self._header(self._time(ns // 1_000_000_000, ns % 1_000_000_000), frame)

    def _quat(self, yaw: float) -> Any:
        return self._quaternion(*yaw_quaternion(yaw))

    def _transform_of(self, time: float, parent: str, child: str, x: float, y: float,
                      yaw: float) -> Any:
        return self._transform_stamped(
            self._stamp(time, parent), child,
            self._transform(self._vector(x, y, 0.0), self._quat(yaw)))

    # ---- messages -------------------------------------------------------------------------

    def scan(self, sample: Sample, header: StreamHeader, scan_time: float) -> bytes | None:
        s = sample.belief.scan
        if s is None:
            return None
        ranges = ros_ranges(s)
        angle_max = s.angle_min + s.angle_increment * (len(ranges) - 1)
        return self._cdr(self._scan(
            self._stamp(sample.time, laser_frame(header)), s.angle_min, angle_max,
            s.angle_increment, 0.0, scan_time, s.range_min, s.range_max, ranges,
            np.zeros(0, dtype=np.float32)), SCAN)

    def odometry(self, sample: Sample, header: StreamHeader) -> bytes:
        x, y, yaw = sample.belief.odom
        linear, angular = sample.belief.odom_twist
        pose = self._pose_cov(self._pose(self._point(x, y, 0.0), self._quat(yaw)),
                              self._covariance)
        twist = self._twist_cov(self._twist(self._vector(linear, 0.0, 0.0),
                                            self._vector(0.0, 0.0, angular)),
                                self._covariance)
        return self._cdr(self._odometry(self._stamp(sample.time, MAP), header.robot.name,
                                        pose, twist), ODOMETRY)

    def command(self, sample: Sample) -> bytes:
        linear, angular = sample.belief.cmd
        return self._cdr(self._twist(self._vector(linear, 0.0, 0.0),
                                     self._vector(0.0, 0.0, angular)), TWIST)

    def transforms(self, sample: Sample, header: StreamHeader, rows: Sequence[int]) -> bytes:
        """The robot's ground-truth pose and those of the objects of ``rows`` (``map`` ->
        body name)."""
        x, y, yaw = sample.robot_pose
        items = [self._transform_of(sample.time, MAP, header.robot.name, x, y, yaw)]
        poses = sample.poses
        for i in rows:
            px, py, pyaw = poses[i].tolist()
            items.append(self._transform_of(sample.time, MAP, header.objects[i].name,
                                            px, py, pyaw))
        return self._cdr(self._tf(items), TF)

    def laser_mount(self, header: StreamHeader, time: float) -> bytes:
        mx, my = header.laser_mount
        return self._cdr(self._tf([self._transform_of(time, header.robot.name,
                                                      laser_frame(header), mx, my, 0.0)]), TF)

    def markers(self, header: StreamHeader, time: float) -> bytes:
        """Every body's footprint as a marker on its own frame, and the floor's tiles."""
        items = [self._body_marker(header.robot, 0, header, time)]
        items += [self._body_marker(o, i + 1, header, time)
                  for i, o in enumerate(header.objects)]
        if header.floors:
            size = header.tile_size
            items.append(self._marker_of(
                self._stamp(time, MAP), "floor", 0, CUBE_LIST,
                self._pose(self._point(0.0, 0.0, -_FLAT / 2), self._identity),
                (size, size, _FLAT), _FLOOR_COLOUR, False,
                [(x, y) for _, x, y in header.floors], "floor"))
        return self._cdr(self._markers(items), MARKERS)

    def _body_marker(self, body: ObservedObject, index: int, header: StreamHeader,
                     time: float) -> Any:
        height = body.height if body.height > 0 else _FLAT
        kind, scale, points = _shape(body.footprint, header.tile_size, height)
        pose = self._pose(self._point(0.0, 0.0, height / 2 if kind != "line" else 0.0),
                          self._identity)
        kinds = {"cube": CUBE, "cylinder": CYLINDER, "line": LINE_STRIP}
        return self._marker_of(self._stamp(time, body.name), body.role, index, kinds[kind],
                               pose, scale, _ROLE_COLOURS[body.role], True, points, body.name)

    def _marker_of(self, stamp: Any, ns: str, index: int, kind: int, pose: Any,
                   scale: tuple[float, float, float], colour: tuple[float, ...],
                   frame_locked: bool, points: list[tuple[float, float]], text: str) -> Any:
        t = self.store.types
        return self._marker(
            header=stamp, ns=ns, id=index, type=kind, action=ADD, pose=pose,
            scale=self._vector(*scale), color=self._colour(*colour),
            lifetime=self._duration(0, 0), frame_locked=frame_locked,
            points=[self._point(x, y, 0.0) for x, y in points], colors=[],
            texture_resource="",
            texture=t["sensor_msgs/msg/CompressedImage"](
                self._header(self._time(0, 0), ""), "", np.zeros(0, dtype=np.uint8)),
            uv_coordinates=[], text=text, mesh_resource="",
            mesh_file=t["visualization_msgs/msg/MeshFile"]("", np.zeros(0, dtype=np.uint8)),
            mesh_use_embedded_materials=False)

    def goal_status(self, index: int, accepted: float, state: NavState) -> bytes:
        """Nav2's navigate_to_pose status as the robot reports the running task ``index``
        (accepted at ``accepted``, simulated seconds): the claim the judge checks."""
        t = self.store.types
        ns = stamp_ns(accepted)
        info = t["action_msgs/msg/GoalInfo"](
            t["unique_identifier_msgs/msg/UUID"](goal_uuid(index)),
            self._time(ns // 1_000_000_000, ns % 1_000_000_000))
        status = t["action_msgs/msg/GoalStatus"](info, GOAL_STATUS_CODE[state])
        return self._cdr(t[GOAL_STATUS]([status]), GOAL_STATUS)

    def sample(self, sample: Sample, header: StreamHeader, rows: Sequence[int],
               scan_time: float) -> list[tuple[str, bytes]]:
        """One sample's ROS 2 messages (topic, CDR), in the order a recording writes them,
        all stamped with the sample's time: /tf (the robot and the objects of ``rows``),
        then the belief the stream collects (``header.data``): /odom, /scan when the laser
        measured, /cmd_vel. Recordings and the live Foxglove view both use it, so the two
        show a run alike."""
        messages = [("/tf", self.transforms(sample, header, rows))]
        data = header.data
        if "odometry" in data:
            messages.append(("/odom", self.odometry(sample, header)))
        if "laser" in data:
            scan = self.scan(sample, header, scan_time)
            if scan is not None:
                messages.append(("/scan", scan))
        if "nav_state" in data:
            messages.append(("/cmd_vel", self.command(sample)))
        return messages

    def text(self, payload: dict[str, Any]) -> bytes:
        return self._cdr(self._string(json.dumps(payload, separators=(",", ":"),
                                                 allow_nan=False, ensure_ascii=False)), TEXT)

    def event(self, event: MissionEvent) -> bytes:
        return self.text(asdict(event))


class MovedBodies:
    """Which observed objects moved since the previous sample (all of them at the first):
    /tf carries a static wall once, as the trace does. One per stream."""

    def __init__(self) -> None:
        self._poses: np.ndarray | None = None

    def rows(self, sample: Sample) -> list[int]:
        old, new = self._poses, sample.poses
        if old is None or old.shape != new.shape:
            rows = list(range(len(new)))
        else:
            rows = np.nonzero((new != old).any(axis=1))[0].tolist()
        self._poses = new.copy()
        return rows


def _shape(fp: Footprint, tile: float, height: float
           ) -> tuple[str, tuple[float, float, float], list[tuple[float, float]]]:
    if isinstance(fp, Box):
        return "cube", (fp.size_x, fp.size_y, height), []
    if isinstance(fp, Cylinder):
        return "cylinder", (2 * fp.radius, 2 * fp.radius, height), []
    if isinstance(fp, Polygon):
        points = list(fp.points)
        return "line", (0.02, 0.0, 0.0), [*points, points[0]]
    return "cube", (tile, tile, height), []


def ros_ranges(scan: LaserScan) -> np.ndarray:
    """A scan's ranges as ``LaserScan.ranges`` holds them: float32, and a beam without a
    return (REI: ``range_max``, its laser clips there) as +inf, as REP 117 asks."""
    ranges = np.asarray(scan.ranges, dtype=np.float32)
    return np.where(ranges >= np.float32(scan.range_max), np.float32(np.inf), ranges)


_CDR_LE = b"\x00\x01\x00\x00"
"""CDR's encapsulation header: plain CDR, little-endian (what rosbags and ROS 2 write)."""


def trace_cdr(line: str) -> bytes:
    """A trace line as a CDR ``std_msgs/msg/String`` (bytes as rosbags serialises them:
    the header, the length with its NUL, the UTF-8 text, the NUL)."""
    data = line.encode("utf-8")
    return _CDR_LE + (len(data) + 1).to_bytes(4, "little") + data + b"\x00"


def trace_line(cdr: bytes) -> bytes | None:
    """The UTF-8 text of a CDR ``std_msgs/msg/String`` (``trace_cdr``'s inverse), or None
    when the bytes are not one."""
    if len(cdr) < 9 or cdr[:4] != _CDR_LE:
        return None
    size = int.from_bytes(cdr[4:8], "little")
    if size < 1 or 8 + size > len(cdr) or cdr[7 + size] != 0 or len(cdr) - 8 - size > 3:
        return None
    return cdr[8:7 + size]


def stamp_ns(time: float) -> int:
    """Simulated seconds as the recording's nanoseconds (the message log time)."""
    return int(round(time * 1e9))


GOAL_STATUS_CODE: dict[NavState, int] = {
    NavState.PENDING: 1,  # STATUS_ACCEPTED
    NavState.ACTIVE: 2,  # STATUS_EXECUTING
    NavState.SUCCEEDED: 4,
    NavState.PREEMPTED: 5,  # STATUS_CANCELED
    NavState.ABORTED: 6,
}
"""REI's navigation states as action_msgs/msg/GoalStatus codes (IDLE has none: no goal)."""


def goal_uuid(index: int) -> np.ndarray:
    """The goal id of the mission's task ``index`` (deterministic: the same run records
    the same bytes): the index, big-endian, in the last bytes of 16."""
    return np.frombuffer((index + 1).to_bytes(16, "big"), dtype=np.uint8).copy()


# ---- ROS -> REI ------------------------------------------------------------------------------

NAV2_STATUS: dict[int, NavState] = {
    1: NavState.PENDING,  # STATUS_ACCEPTED: accepted, awaiting execution
    2: NavState.ACTIVE,  # STATUS_EXECUTING
    3: NavState.ACTIVE,  # STATUS_CANCELING
    4: NavState.SUCCEEDED,  # STATUS_SUCCEEDED
    5: NavState.PREEMPTED,  # STATUS_CANCELED
    6: NavState.ABORTED,  # STATUS_ABORTED
}
"""action_msgs/msg/GoalStatus codes as the navigation states of REI's mission executor.
STATUS_UNKNOWN (0) has none: action_msgs defines it as a status "not properly set", which
says nothing about the goal, so each reader decides what such a status leaves (a recording
keeps the goal pending; the live action client ignores it and aborts a result carrying it)."""

STATUS_UNKNOWN = 0
"""action_msgs/msg/GoalStatus.STATUS_UNKNOWN: the one code without a navigation state."""


def yaw_quaternion(yaw: float) -> tuple[float, float, float, float]:
    """A heading as a quaternion (x, y, z, w) about z (``yaw_of``'s inverse)."""
    return (0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0))


def seconds(stamp: Any) -> float:
    """A builtin_interfaces/msg/Time as seconds."""
    return float(stamp.sec) + float(stamp.nanosec) * 1e-9


def yaw_of(q: Any) -> float:
    """The rotation about z of a quaternion (x, y, z, w), in (-pi, pi]: a planar robot's
    heading (roll and pitch are ignored)."""
    x, y, z, w = float(q.x), float(q.y), float(q.z), float(q.w)
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def pose_of(transform: Any) -> tuple[float, float, float]:
    """(x, y, yaw) of a geometry_msgs/msg/Transform or Pose (translation or position)."""
    t = getattr(transform, "translation", None) or transform.position
    q = getattr(transform, "rotation", None) or transform.orientation
    return float(t.x), float(t.y), yaw_of(q)


def odometry_of(message: Any) -> tuple[tuple[float, float, float], tuple[float, float]]:
    """((x, y, yaw), (linear, angular)) of a nav_msgs/msg/Odometry: REI's odometry belief."""
    twist = message.twist.twist
    return pose_of(message.pose.pose), (float(twist.linear.x), float(twist.angular.z))


def command_of(message: Any) -> tuple[float, float]:
    """(linear, angular) of a geometry_msgs/msg/Twist (or a TwistStamped's twist)."""
    twist = getattr(message, "twist", message)
    return float(twist.linear.x), float(twist.angular.z)


def scan_of(message: Any) -> LaserScan:
    """A sensor_msgs/msg/LaserScan as REI's scan: ranges as float64, a beam without a return
    (+inf, REP 117) at range_max as REI's laser reports it; NaN (an erroneous reading) and
    -inf stay, for the monitor to refuse."""
    ranges = np.asarray(message.ranges, dtype=np.float64)
    range_max = float(message.range_max)
    ranges = np.where(np.isposinf(ranges), range_max, ranges)
    return LaserScan(float(message.angle_min), float(message.angle_increment),
                     float(message.range_min), range_max, ranges)


def scan_geometry_problem(message: Any) -> str:
    """Why a sensor_msgs/msg/LaserScan's header does not describe its own ranges (the
    angles must step from angle_min to angle_max by angle_increment, one range per
    step), or ''."""
    n = len(message.ranges)
    low, high, inc = (float(message.angle_min), float(message.angle_max),
                      float(message.angle_increment))
    if not all(map(math.isfinite, (low, high, inc))) or inc == 0.0:
        return (f"finite angles and a non-zero angle_increment, found angle_min {low!r}, "
                f"angle_max {high!r}, angle_increment {inc!r}")
    steps = (high - low) / inc + 1.0
    if n == 0 or abs(steps - n) > 0.5 + 1e-3 * n:
        return (f"{round(steps)} ranges (angle_min {low:.7g} to angle_max {high:.7g} in steps "
                f"of {inc:.7g}), found {n}")
    return ""
