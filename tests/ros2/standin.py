"""A stand-in ROS 2 navigation node written directly on Zenoh and rosbags' CDR (no REI code).

It follows rmw_zenoh's published format (ros2/rmw_zenoh docs/design.md @ 99a6a2bd): key
expressions ``<domain>/<name>/<pkg>::<kind>::dds_::<Type>_/<hash>``, liveliness tokens
``@ros2_lv/...``, the attachment as Zenoh's own serializer writes it (``z_serialize`` of
int64, int64 and a sequence of 16 uint8), services as complete queryables answered with
the request's sequence number and client GID. It imports nothing from ``rei.runtime.bus.ros2``:
a mistake there cannot cancel out here.

Like a small Nav2 it subscribes ``/odom``, ``/scan`` and ``/clock``, publishes ``/cmd_vel``
(a turn-then-drive law toward the goal, one command per odometry message, as a controller
on sim time answers each new state), and serves ``navigate_to_pose``: send_goal accepts,
get_result answers SUCCEEDED (4) when odometry is within ``reach`` metres of the goal, the
status topic follows, cancel_goal cancels.
"""

from __future__ import annotations

import math
import threading
import time
from typing import Any

import numpy as np
import zenoh
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from zenoh.ext import Int64, UInt8, z_serialize

HASHLESS = "TypeHashNotSupported"  # ROS 2 Humble's rmw_zenoh_cpp
ACTION = "nav2_msgs/action/NavigateToPose"

# ros-navigation/navigation2 nav2_msgs/action/NavigateToPose.action, branch humble
# (3c3db59d6969d8ecee8e68468693d006397f4a0c), and the types rosidl derives from it;
# ros2/rcl_interfaces action_msgs/srv/CancelGoal.srv (f5b4ab352c9658daf068150aeda08ef48fa56ce4).
_HUMBLE_ACTION = {
    "Goal": "geometry_msgs/PoseStamped pose\nstring behavior_tree\n",
    "Result": "std_msgs/Empty result\n",
    "Feedback": "geometry_msgs/PoseStamped current_pose\nbuiltin_interfaces/Duration "
                "navigation_time\nbuiltin_interfaces/Duration estimated_time_remaining\n"
                "int16 number_of_recoveries\nfloat32 distance_remaining\n",
    "SendGoal_Request": "unique_identifier_msgs/UUID goal_id\nnav2msgs_placeholder_Goal goal\n",
    "SendGoal_Response": "bool accepted\nbuiltin_interfaces/Time stamp\n",
    "GetResult_Request": "unique_identifier_msgs/UUID goal_id\n",
    "GetResult_Response": "int8 status\nnav2msgs_placeholder_Result result\n",
    "FeedbackMessage": "unique_identifier_msgs/UUID goal_id\n"
                       "nav2msgs_placeholder_Feedback feedback\n",
}
_CANCEL = {"Request": "action_msgs/GoalInfo goal_info\n",
           "Response": "int8 return_code\naction_msgs/GoalInfo[] goals_canceling\n"}


# branch jazzy (f4108e5b1c2bce804a1aa0c7be6673a8eb4a1501): the result's fields changed
_JAZZY_RESULT = "uint16 error_code\nstring error_msg\n"


def humble_store(jazzy: bool = False) -> Any:
    """rosbags' Humble (or Jazzy) store with NavigateToPose and CancelGoal, registered under
    the names the wire uses (rosbags' parser files every type under .../msg/)."""
    store = get_typestore(Stores.ROS2_JAZZY if jazzy else Stores.ROS2_HUMBLE)
    types: dict[str, Any] = {}
    for part, text in _HUMBLE_ACTION.items():
        if jazzy and part == "Result":
            text = _JAZZY_RESULT
        text = text.replace("nav2msgs_placeholder_", "nav2_msgs/msg/NavigateToPose_")
        types.update(get_types_from_msg(text, f"nav2_msgs/msg/NavigateToPose_{part}"))
    for part, text in _CANCEL.items():
        types.update(get_types_from_msg(text, f"action_msgs/msg/CancelGoal_{part}"))
    store.register({_wire(name): _wire(definition) for name, definition in types.items()})
    return store


# REP 2011's RIHS01, written here from the REP and type_description_interfaces'
# FieldType.msg (not with rosbags' hash_rihs01, nor rei.runtime.bus.ros2's): SHA-256 of the JSON
# of the type's description and its referenced descriptions sorted by name; a field is
# {name, type: {type_id, capacity, string_capacity, nested_type_name}}; arrays add 48,
# bounded sequences 96, unbounded 144 to the element's id; a .msg char is uint8 (rosidl).
_FIELD_TYPE = {"int8": 2, "uint8": 3, "char": 3, "int16": 4, "uint16": 5, "int32": 6,
               "uint32": 7, "int64": 8, "uint64": 9, "float32": 10, "float64": 11,
               "bool": 15, "byte": 16, "string": 17}


def rihs01(fields_of: Any, name: str) -> str:
    import hashlib
    import json
    described: dict[str, Any] = {}

    def element(definition: Any) -> tuple[int, int, str]:
        kind, detail = definition
        if int(kind) == 2:  # a nested type
            describe(detail)
            return 1, 0, detail
        base, bound = detail
        if base == "string" and bound:
            return 21, bound, ""
        return _FIELD_TYPE[base], 0, ""

    def field(fname: str, definition: Any) -> dict[str, Any]:
        kind, detail = definition
        capacity, offset = 0, 0
        if int(kind) == 3:  # array
            definition, capacity, offset = detail[0], detail[1], 48
        elif int(kind) == 4:  # sequence
            definition, capacity = detail[0], detail[1]
            offset = 96 if capacity else 144
        type_id, string_capacity, nested = element(definition)
        return {"name": fname, "type": {"type_id": type_id + offset, "capacity": capacity,
                                        "string_capacity": string_capacity,
                                        "nested_type_name": nested}}

    def describe(typename: str) -> None:
        if typename in described:
            return
        described[typename] = None
        fields = fields_of[typename][1] or [
            ("structure_needs_at_least_one_member", (1, ("uint8", 0)))]
        described[typename] = {"type_name": typename,
                               "fields": [field(n, d) for n, d in fields]}

    describe(name)
    body = {"type_description": described[name],
            "referenced_type_descriptions": [described[k] for k in sorted(described)
                                             if k != name]}
    return "RIHS01_" + hashlib.sha256(json.dumps(body).encode()).hexdigest()


def jazzy_hashes() -> dict[str, str]:
    """The RIHS01 of every DDS type the stand-in meets, services included (a service is
    described by request_message, response_message and the _Event rosidl derives)."""
    store = humble_store(jazzy=True)
    fields_of = dict(store.fielddefs)
    for service in (f"{ACTION}_SendGoal", f"{ACTION}_GetResult", "action_msgs/srv/CancelGoal"):
        fields_of[f"{service}_Event"] = ([], [
            ("info", (2, "service_msgs/msg/ServiceEventInfo")),
            ("request", (4, ((2, f"{service}_Request"), 1))),
            ("response", (4, ((2, f"{service}_Response"), 1)))])
        fields_of[service] = ([], [("request_message", (2, f"{service}_Request")),
                                   ("response_message", (2, f"{service}_Response")),
                                   ("event_message", (2, f"{service}_Event"))])
    names = ["geometry_msgs/msg/Twist", "nav_msgs/msg/Odometry", "sensor_msgs/msg/LaserScan",
             "rosgraph_msgs/msg/Clock", "geometry_msgs/msg/PoseStamped",
             "action_msgs/msg/GoalStatusArray", f"{ACTION}_FeedbackMessage",
             f"{ACTION}_SendGoal", f"{ACTION}_GetResult", "action_msgs/srv/CancelGoal"]
    return {_dds(n): rihs01(fields_of, n) for n in names}


def _dds(msgtype: str) -> str:
    package, kind, name = msgtype.split("/")
    return f"{package}::{kind}::dds_::{name}_"


def _wire(item: Any) -> Any:
    if isinstance(item, str):
        return (item.replace("nav2_msgs/msg/NavigateToPose_", "nav2_msgs/action/NavigateToPose_")
                .replace("action_msgs/msg/CancelGoal_", "action_msgs/srv/CancelGoal_"))
    if isinstance(item, tuple):
        return tuple(_wire(part) for part in item)
    if isinstance(item, list):
        return [_wire(part) for part in item]
    return item


def key(domain: int, name: str, dds_type: str, type_hash: str = HASHLESS) -> str:
    return f"{domain}/{name}/{dds_type}/{type_hash}"


def attachment(sequence: int, gid: bytes) -> bytes:
    return z_serialize((Int64(sequence), Int64(time.time_ns()),
                        [UInt8(b) for b in gid])).to_bytes()


def read_attachment(data: bytes) -> tuple[int, int, bytes]:
    """(sequence, timestamp, gid) -- parsed by hand from the documented layout."""
    assert len(data) == 33 and data[16] == 16, data
    return (int.from_bytes(data[0:8], "little", signed=True),
            int.from_bytes(data[8:16], "little", signed=True), bytes(data[17:33]))


class StandInNav2:
    """The stand-in: ``start()``, then it drives whoever publishes /odom; ``close()``."""

    def __init__(self, router: str, domain: int = 0, reach: float = 0.12,
                 type_hash: dict[str, str] | None = None,
                 auth: tuple[str, str] | None = None, namespace: str = "",
                 jazzy: bool = False) -> None:
        self.auth, self.jazzy = auth, jazzy
        self.ns = namespace  # "robot1/" puts the robot's topics and action under /robot1
        self.router, self.domain, self.reach = router, domain, reach
        self.max_linear = 0.22  # under the robot's drive limit, as a Nav2 config would be
        self.hashes = type_hash or (jazzy_hashes() if jazzy else {})
        self.store = humble_store(jazzy)
        self.lock = threading.Lock()
        self.goal: tuple[bytes, float, float] | None = None
        self.result_queries: dict[bytes, Any] = {}
        self.counts = {"odom": 0, "scan": 0, "clock": 0, "cmd_vel": 0, "goals": 0,
                       "cancels": 0, "bad_attachment": 0, "goal_pose": 0}
        self.scan_beams: set[int] = set()
        self.scan_no_return = self.scan_at_max = 0
        self.clock_ns: list[int] = []
        self.gid = bytes(range(200, 216))
        self.sequence = 0
        self.declared: list[Any] = []

    def _hash(self, dds: str) -> str:
        return self.hashes.get(dds, HASHLESS)

    def _key(self, name: str, dds: str) -> str:
        return key(self.domain, name, dds, self._hash(dds))

    def start(self) -> StandInNav2:
        config = zenoh.Config()
        config.insert_json5("mode", '"client"')
        config.insert_json5("connect/endpoints", f'["{self.router}"]')
        config.insert_json5("scouting/multicast/enabled", "false")
        if self.auth is not None:
            config.insert_json5("transport/auth/usrpwd/user", f'"{self.auth[0]}"')
            config.insert_json5("transport/auth/usrpwd/password", f'"{self.auth[1]}"')
        self.session = zenoh.open(config)
        d, s = self.domain, self.session
        zid = str(s.zid())
        twist = "geometry_msgs::msg::dds_::Twist_"
        self.cmd_key = key(d, f"{self.ns}cmd_vel", twist, self._hash(twist))
        self.cmd_pub = s.declare_publisher(self.cmd_key)
        odom = "nav_msgs::msg::dds_::Odometry_"
        scan = "sensor_msgs::msg::dds_::LaserScan_"
        clock = "rosgraph_msgs::msg::dds_::Clock_"
        action = f"{self.ns}navigate_to_pose/_action"
        mangled = self.ns.replace("/", "%")
        send_goal = "nav2_msgs::action::dds_::NavigateToPose_SendGoal_"
        tokens = [f"@ros2_lv/{d}/{zid}/0/0/NN/%/%/standin_nav2",
                  f"@ros2_lv/{d}/{zid}/0/11/SS/%/%/standin_nav2/%{mangled}navigate_to_pose"
                  f"%_action%send_goal/{send_goal}/{self._hash(send_goal)}/::,10:,:,:,,",
                  f"@ros2_lv/{d}/{zid}/0/10/MP/%/%/standin_nav2/%{mangled}cmd_vel/{twist}/"
                  f"{self._hash(twist)}/::,10:,:,:,,"]
        self.declared += [s.liveliness().declare_token(t) for t in tokens]
        self.declared += [
            s.declare_subscriber(key(d, f"{self.ns}odom", odom, self._hash(odom)), self._on_odom),
            s.declare_subscriber(key(d, f"{self.ns}scan", scan, self._hash(scan)), self._on_scan),
            s.declare_subscriber(key(d, "clock", clock, self._hash(clock)), self._on_clock),
            s.declare_queryable(self._key(f"{action}/send_goal", send_goal),
                                self._on_send_goal, complete=True),
            s.declare_queryable(self._key(f"{action}/get_result",
                                          "nav2_msgs::action::dds_::NavigateToPose_GetResult_"),
                                self._on_get_result, complete=True),
            s.declare_queryable(self._key(f"{action}/cancel_goal",
                                          "action_msgs::srv::dds_::CancelGoal_"),
                                self._on_cancel, complete=True),
        ]
        pose = "geometry_msgs::msg::dds_::PoseStamped_"
        self.declared.append(s.declare_subscriber(self._key(f"{self.ns}goal_pose", pose),
                                                  self._on_goal_pose))
        self.status_pub = s.declare_publisher(
            self._key(f"{action}/status", "action_msgs::msg::dds_::GoalStatusArray_"))
        return self

    def close(self) -> None:
        for item in reversed(self.declared):
            item.undeclare()
        self.session.close()

    # ---- topics ---------------------------------------------------------------------------

    def _decode(self, sample: Any, msgtype: str) -> Any:
        try:
            read_attachment(sample.attachment.to_bytes())
        except (AssertionError, AttributeError):
            self.counts["bad_attachment"] += 1
        return self.store.deserialize_cdr(sample.payload.to_bytes(), msgtype)

    def _on_clock(self, sample: Any) -> None:
        message = self._decode(sample, "rosgraph_msgs/msg/Clock")
        with self.lock:
            self.counts["clock"] += 1
            self.clock_ns.append(message.clock.sec * 10**9 + message.clock.nanosec)

    def _on_scan(self, sample: Any) -> None:
        message = self._decode(sample, "sensor_msgs/msg/LaserScan")
        with self.lock:
            self.counts["scan"] += 1
            self.scan_beams.add(len(message.ranges))
            self.scan_no_return += int(np.isposinf(message.ranges).sum())
            self.scan_at_max += int((message.ranges == message.range_max).sum())

    def _on_odom(self, sample: Any) -> None:
        message = self._decode(sample, "nav_msgs/msg/Odometry")
        p, q = message.pose.pose.position, message.pose.pose.orientation
        yaw = 2.0 * math.atan2(q.z, q.w)
        with self.lock:
            self.counts["odom"] += 1
            goal = self.goal
        linear = angular = 0.0
        if goal is not None:
            uuid, gx, gy = goal
            distance = math.hypot(gx - p.x, gy - p.y)
            if distance <= self.reach:
                self._finish(uuid, 4)
            else:
                error = math.remainder(math.atan2(gy - p.y, gx - p.x) - yaw, math.tau)
                angular = max(-1.0, min(1.0, 2.0 * error))
                linear = 0.0 if abs(error) > 0.35 else min(self.max_linear, distance)
        t = self.store.types
        vector = t["geometry_msgs/msg/Vector3"]
        payload = bytes(self.store.serialize_cdr(
            t["geometry_msgs/msg/Twist"](vector(linear, 0.0, 0.0), vector(0.0, 0.0, angular)),
            "geometry_msgs/msg/Twist"))
        with self.lock:
            self.sequence += 1
            sequence = self.sequence
            self.counts["cmd_vel"] += 1
        self.cmd_pub.put(payload, attachment=attachment(sequence, self.gid))

    def _on_goal_pose(self, sample: Any) -> None:
        """RViz's "2D Goal Pose" topic: a goal without an answer (no action)."""
        message = self._decode(sample, "geometry_msgs/msg/PoseStamped")
        position = message.pose.position
        with self.lock:
            self.counts["goal_pose"] += 1
            self.goal = (b"topic", float(position.x), float(position.y))

    # ---- the action -----------------------------------------------------------------------

    def _reply(self, query: Any, message: Any, msgtype: str) -> None:
        sequence, _, client_gid = read_attachment(query.attachment.to_bytes())
        query.reply(query.key_expr, bytes(self.store.serialize_cdr(message, msgtype)),
                    attachment=attachment(sequence, client_gid))

    def _on_send_goal(self, query: Any) -> None:
        request = self.store.deserialize_cdr(
            query.payload.to_bytes(), f"{ACTION}_SendGoal_Request")
        uuid = bytes(request.goal_id.uuid)
        position = request.goal.pose.pose.position
        assert request.goal.pose.header.frame_id == "map"
        with self.lock:
            self.goal = (uuid, float(position.x), float(position.y))
            self.counts["goals"] += 1
        t = self.store.types
        self._reply(query, t[f"{ACTION}_SendGoal_Response"](
            True, t["builtin_interfaces/msg/Time"](0, 0)), f"{ACTION}_SendGoal_Response")
        query.drop()
        self._status(uuid, 2)

    def _on_get_result(self, query: Any) -> None:
        request = self.store.deserialize_cdr(
            query.payload.to_bytes(), f"{ACTION}_GetResult_Request")
        with self.lock:  # answered when the goal ends (the query stays open until then)
            self.result_queries[bytes(request.goal_id.uuid)] = query

    def _on_cancel(self, query: Any) -> None:
        request = self.store.deserialize_cdr(query.payload.to_bytes(),
                                             "action_msgs/srv/CancelGoal_Request")
        uuid = bytes(request.goal_info.goal_id.uuid)
        with self.lock:
            self.counts["cancels"] += 1
        # the goal ends before the answer goes: a client that goes on (or resets and sends a
        # goal with the same id) once answered never meets this cancel finishing late
        self._finish(uuid, 5)
        t = self.store.types
        self._reply(query, t["action_msgs/srv/CancelGoal_Response"](0, []),
                    "action_msgs/srv/CancelGoal_Response")
        query.drop()

    def _finish(self, uuid: bytes, status: int) -> None:
        with self.lock:
            if self.goal is not None and self.goal[0] == uuid:
                self.goal = None
            query = self.result_queries.pop(uuid, None)
        self._status(uuid, status)
        if query is not None:
            t = self.store.types
            result = t[f"{ACTION}_Result"](0, "") if self.jazzy else \
                t[f"{ACTION}_Result"](t["std_msgs/msg/Empty"]())
            self._reply(query, t[f"{ACTION}_GetResult_Response"](status, result),
                        f"{ACTION}_GetResult_Response")
            query.drop()

    def _status(self, uuid: bytes, status: int) -> None:
        t = self.store.types
        info = t["action_msgs/msg/GoalInfo"](
            t["unique_identifier_msgs/msg/UUID"](np.frombuffer(uuid, dtype=np.uint8).copy()),
            t["builtin_interfaces/msg/Time"](0, 0))
        message = t["action_msgs/msg/GoalStatusArray"]([t["action_msgs/msg/GoalStatus"](
            info, status)])
        with self.lock:
            self.sequence += 1
            sequence = self.sequence
        self.status_pub.put(bytes(self.store.serialize_cdr(
            message, "action_msgs/msg/GoalStatusArray")), attachment=attachment(sequence,
                                                                                 self.gid))


def wait_for(condition: Any, seconds: float) -> bool:
    """Poll ``condition`` for at most ``seconds`` (bounded; never a wall-clock assertion)."""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        if condition():
            return True
        time.sleep(0.02)
    return bool(condition())
