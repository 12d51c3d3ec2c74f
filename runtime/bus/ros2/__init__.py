"""ROS 2 on the wire: a ROS 2 stack on rmw_zenoh_cpp as REI's robot under test, without ROS.

``names`` (key expressions, liveliness tokens, QoS), ``attachment`` (the 33-byte rmw_zenoh
attachment), ``types`` (rosbags' type store with Nav2's action, type hashes RIHS01 or
Humble's), ``node`` (a node on the wire), ``nav2`` (the navigate_to_pose client),
``adapter`` (the Controller, ``--controller ros2:...``) and ``profile`` (key expressions per
role for the router's rules). See docs/ros2.md. Importing this package opens nothing; Zenoh
is imported when a session is opened.
"""

from rei.runtime.bus.ros2.adapter import Ros2Controller, Ros2Options, parse_options
from rei.runtime.bus.ros2.attachment import Attachment
from rei.runtime.bus.ros2.errors import Ros2Error
from rei.runtime.bus.ros2.names import Distro, EntityKind, EntityToken, QosProfile, parse_token
from rei.runtime.bus.ros2.profile import RoleKeys, access_rules, endpoints
from rei.runtime.bus.ros2.types import type_hash, typestore

__all__ = [
    "Attachment",
    "Distro",
    "EntityKind",
    "EntityToken",
    "QosProfile",
    "Ros2Controller",
    "Ros2Error",
    "Ros2Options",
    "RoleKeys",
    "access_rules",
    "endpoints",
    "parse_options",
    "parse_token",
    "type_hash",
    "typestore",
]
