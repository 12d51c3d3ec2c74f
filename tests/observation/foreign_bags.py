"""ROS 2 bags REI did not make, written with rosbags' own ``Writer`` (an independent writer):
a TurtleBot driving simple_wall's mission as a Gazebo run with Nav2 would record it, and the
ways such a bag goes wrong."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

STORE = get_typestore(Stores.ROS2_HUMBLE)
T = STORE.types


@dataclass(frozen=True)
class Drive:
    """One drive of simple_wall's robot ``waffle`` along y = 0 (stamps in seconds)."""

    stop_x: float = 1.8
    """Where the robot stops (the second goal, 'front', is at x = 2, tolerance 0.25: within
    it, so the robot's travel after the task's success at x = 1.75 is 0.05 m and the default
    SETTLE requirement holds)."""
    rate: float = 10.0
    duration: float = 12.0
    """Recorded seconds: arrival at 7.2 s, then the mission's 3 s settle period (the mission
    ends at its end, as a live run does: a recording that stops sooner is cut short)."""
    speed: float = 0.25
    nav2: bool = False
    """Also record Nav2's navigate_to_pose status (task 0 at once, task 1 on arrival)."""
    claim_success_at: float | None = None
    """With nav2: when the stack says SUCCEEDED for the second goal (default: on arrival)."""
    storage: StoragePlugin = StoragePlugin.MCAP
    parent: str = "map"
    robot: str = "waffle"
    scan_beams: int = 360
    scan_ranges: int | None = None
    """Ranges written per scan (default: scan_beams, as the header says)."""
    y: float = 0.0
    """The lane driven (simple_wall's walls face it at y = +-0.5)."""
    scan_increment: float | None = None
    drop: tuple[str, ...] = ()
    """Topics left out."""
    gap: tuple[float, float] | None = None
    """No /tf between these times (s)."""
    backwards_at: float | None = None
    """The /tf stamp of this sample goes back 0.5 s."""
    nan_at: float | None = None
    """The robot's pose is NaN at this sample."""
    extra: dict[str, int] = field(default_factory=dict)
    """Topic -> number of std_msgs/String messages of a topic REI does not read."""

    def x_at(self, t: float) -> float:
        return min(self.stop_x, self.speed * t)


def _stamp(t: float) -> Any:
    ns = int(round(t * 1e9))
    return T["builtin_interfaces/msg/Time"](ns // 10**9, ns % 10**9)


def _header(t: float, frame: str) -> Any:
    return T["std_msgs/msg/Header"](_stamp(t), frame)


def _quat(yaw: float) -> Any:
    return T["geometry_msgs/msg/Quaternion"](0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))


def _vector(x: float, y: float, z: float = 0.0) -> Any:
    return T["geometry_msgs/msg/Vector3"](x, y, z)


def _tf(t: float, parent: str, child: str, x: float, y: float, yaw: float) -> Any:
    return T["tf2_msgs/msg/TFMessage"]([T["geometry_msgs/msg/TransformStamped"](
        _header(t, parent), child,
        T["geometry_msgs/msg/Transform"](_vector(x, y), _quat(yaw)))])


def _odom(t: float, x: float, v: float) -> Any:
    cov = np.zeros(36)
    pose = T["geometry_msgs/msg/PoseWithCovariance"](
        T["geometry_msgs/msg/Pose"](T["geometry_msgs/msg/Point"](x, 0.0, 0.0), _quat(0.0)), cov)
    twist = T["geometry_msgs/msg/TwistWithCovariance"](
        T["geometry_msgs/msg/Twist"](_vector(v, 0.0), _vector(0.0, 0.0)), cov)
    return T["nav_msgs/msg/Odometry"](_header(t, "odom"), "base_footprint", pose, twist)


def _scan(t: float, drive: Drive) -> Any:
    n = drive.scan_beams
    inc = drive.scan_increment if drive.scan_increment is not None else 2 * math.pi / n
    ranges = np.full(drive.scan_ranges if drive.scan_ranges is not None else n, 0.9,
                     dtype=np.float32)
    ranges[: n // 4] = np.inf  # no return behind the robot (REP 117)
    return T["sensor_msgs/msg/LaserScan"](
        _header(t, "base_scan"), -math.pi, -math.pi + inc * (n - 1), inc, 0.0, 0.2, 0.12, 3.5,
        ranges, np.zeros(0, dtype=np.float32))


def _status(goals: list[tuple[int, float, int]]) -> Any:
    out = []
    for index, accepted, code in goals:
        uuid = np.frombuffer((index + 7).to_bytes(16, "big"), dtype=np.uint8).copy()
        out.append(T["action_msgs/msg/GoalStatus"](
            T["action_msgs/msg/GoalInfo"](T["unique_identifier_msgs/msg/UUID"](uuid),
                                          _stamp(accepted)), code))
    return T["action_msgs/msg/GoalStatusArray"](out)


def write_bag(path: Path, drive: Drive = Drive()) -> Path:
    """The bag of ``drive`` at ``path`` (an MCAP or sqlite3 rosbag2 folder)."""
    types = {"/tf": "tf2_msgs/msg/TFMessage", "/odom": "nav_msgs/msg/Odometry",
             "/scan": "sensor_msgs/msg/LaserScan", "/cmd_vel": "geometry_msgs/msg/Twist",
             "/clock": "rosgraph_msgs/msg/Clock"}
    if drive.nav2:
        types["/navigate_to_pose/_action/status"] = "action_msgs/msg/GoalStatusArray"
    with Writer(path, version=9, storage_plugin=drive.storage) as writer:
        conns = {topic: writer.add_connection(topic, msgtype, typestore=STORE)
                 for topic, msgtype in types.items() if topic not in drive.drop}
        extra = {topic: writer.add_connection(topic, "std_msgs/msg/String", typestore=STORE)
                 for topic in drive.extra}

        def put(topic: str, t: float, message: Any) -> None:
            if topic in conns:
                writer.write(conns[topic], int(round(t * 1e9)),
                             bytes(STORE.serialize_cdr(message, types[topic])))

        arrived = drive.duration
        n = int(round(drive.duration * drive.rate))
        for k in range(n + 1):
            t = k / drive.rate
            x = drive.x_at(t)
            moving = x < drive.stop_x
            if not moving and arrived == drive.duration:
                arrived = t
            put("/clock", t, T["rosgraph_msgs/msg/Clock"](_stamp(t)))
            if drive.gap is None or not drive.gap[0] <= t < drive.gap[1]:
                stamp = t - 0.5 if drive.backwards_at is not None and \
                    abs(t - drive.backwards_at) < 1e-9 else t
                pose_x = math.nan if drive.nan_at is not None and \
                    abs(t - drive.nan_at) < 1e-9 else x
                put("/tf", t, _tf(stamp, drive.parent, drive.robot, pose_x, drive.y, 0.0))
            put("/odom", t, _odom(t, x, drive.speed if moving else 0.0))
            put("/cmd_vel", t, T["geometry_msgs/msg/Twist"](
                _vector(drive.speed if moving else 0.0, 0.0), _vector(0.0, 0.0)))
            if k % 2 == 0:
                put("/scan", t, _scan(t, drive))
            if drive.nav2:
                claim = drive.claim_success_at if drive.claim_success_at is not None \
                    else arrived
                second = [(1, 0.1, 4 if t >= claim else 2)] if t >= 0.1 else []
                put("/navigate_to_pose/_action/status", t,
                    _status([(0, 0.0, 4 if t >= 0.1 else 2), *second]))
        for topic, count in drive.extra.items():
            data = bytes(STORE.serialize_cdr(T["std_msgs/msg/String"]("x"),
                                             "std_msgs/msg/String"))
            for i in range(count):
                writer.write(extra[topic], i * 1000, data)
    return path


def variant(**changes: Any) -> Drive:
    return replace(Drive(), **changes)


Edit = Callable[[Drive], Drive]
