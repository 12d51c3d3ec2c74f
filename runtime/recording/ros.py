"""The ROS 2 views of the sample stream: messages of the standard ROS 2 types, CDR-encoded.

Built with rosbags' type store of ROS 2 Humble (no ROS installation needed); each topic's
schema is the type's ``ros2msg`` definition with its dependencies, as `ros2 bag` records
it, so Foxglove and ROS 2 tools decode the recording. These views lose precision (ranges
are float32, yaw becomes a quaternion): the exact record is the /rei/trace channel.

Frames: ``map`` is the world; each body (the robot and every observed object) has the
frame of its name, placed by /tf with its ground-truth pose; the laser is the robot's frame
``ROBOT/laser`` at the laser's mount (/tf_static). The world's markers hang on the bodies'
frames (``frame_locked``), so moving bodies carry their markers. This module must never
import pybullet.
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
from rei.runtime.messages import LaserScan, MissionEvent, ObservedObject, Sample, StreamHeader

STORE = Stores.ROS2_HUMBLE

SCAN = "sensor_msgs/msg/LaserScan"
ODOMETRY = "nav_msgs/msg/Odometry"
TWIST = "geometry_msgs/msg/Twist"
TF = "tf2_msgs/msg/TFMessage"
MARKERS = "visualization_msgs/msg/MarkerArray"
TEXT = "std_msgs/msg/String"

TOPICS: dict[str, str] = {
    "/scan": SCAN,
    "/odom": ODOMETRY,
    "/cmd_vel": TWIST,
    "/tf": TF,
    "/tf_static": TF,
    "/world/markers": MARKERS,
    "/rei/events": TEXT,
    "/rei/signals": TEXT,
}
"""Every ROS 2 topic of a recording and its message type."""

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
        return self._quaternion(0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0))

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

    def text(self, payload: dict[str, Any]) -> bytes:
        return self._cdr(self._string(json.dumps(payload, separators=(",", ":"),
                                                 allow_nan=False, ensure_ascii=False)), TEXT)

    def event(self, event: MissionEvent) -> bytes:
        return self.text(asdict(event))


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
