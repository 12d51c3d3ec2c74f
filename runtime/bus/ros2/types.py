"""The ROS 2 types of the robot-facing profile: rosbags' type store, Nav2's action, type hashes.

The message types (LaserScan, Odometry, Twist, TFMessage, Clock, PoseStamped,
GoalStatusArray) come from rosbags' store of the chosen distribution. What that store lacks
is registered here from the published definitions:

- ``nav2_msgs/action/NavigateToPose`` from ros-navigation/navigation2
  ``nav2_msgs/action/NavigateToPose.action`` -- branch humble at commit
  3c3db59d6969d8ecee8e68468693d006397f4a0c (result ``std_msgs/Empty result``) and branch
  jazzy at commit f4108e5b1c2bce804a1aa0c7be6673a8eb4a1501 (result ``uint16 error_code``,
  ``string error_msg``; kilted has the same fields);
- ``action_msgs/srv/CancelGoal`` from ros2/rcl_interfaces ``action_msgs/srv/CancelGoal.srv``
  as last changed by commit f5b4ab352c9658daf068150aeda08ef48fa56ce4 (the same on the
  humble and jazzy branches: ``int8 return_code``, ``GoalInfo[] goals_canceling``);
- the types rosidl derives from an action (ros2/rosidl ``rosidl_parser/definition.py``,
  class ``Action``, commit 854b5e97c26fadb24229096ae8541bbb495588dd): ``_SendGoal``
  (request: UUID goal_id, Goal goal; response: bool accepted, Time stamp), ``_GetResult``
  (request: UUID goal_id; response: int8 status, Result result) and ``_FeedbackMessage``
  (UUID goal_id, Feedback feedback); and from a service (class ``Service``) its ``_Event``
  (ServiceEventInfo info, Request[<=1] request, Response[<=1] response).

Type hashes: Humble's rmw_zenoh writes ``TypeHashNotSupported``; Jazzy and later write the
RIHS01 hash of REP 2011, which rosbags computes for a message (``Typestore.hash_rihs01``).
A service's hash is that of its type description with the fields ``request_message``,
``response_message`` and ``event_message``, computed the same way over a store where those
descriptions are registered; ``char`` fields are described as ``uint8`` there, as rosidl
does (rosbags describes ``char`` with its own type id, which gives another hash for
``service_msgs/msg/ServiceEventInfo.client_gid`` and so for every service; the pinned
``example_interfaces/srv/AddTwoInts`` golden of rmw_zenoh's design document tells the two
apart). This module must never open a session.
"""

from __future__ import annotations

from functools import cache
from typing import Any

from rosbags.interfaces import Nodetype
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

from rei.runtime.bus.ros2.errors import Ros2Error
from rei.runtime.bus.ros2.names import HASH_NOT_SUPPORTED, Distro

NAVIGATE_TO_POSE = "nav2_msgs/action/NavigateToPose"
CANCEL_GOAL = "action_msgs/srv/CancelGoal"
GOAL_STATUS_ARRAY = "action_msgs/msg/GoalStatusArray"
CLOCK = "rosgraph_msgs/msg/Clock"
POSE_STAMPED = "geometry_msgs/msg/PoseStamped"

_STORES = {Distro.HUMBLE: Stores.ROS2_HUMBLE, Distro.JAZZY: Stores.ROS2_JAZZY}

_NAVIGATE_GOAL = "geometry_msgs/PoseStamped pose\nstring behavior_tree\n"
_NAVIGATE_RESULT = {
    Distro.HUMBLE: "std_msgs/Empty result\n",
    Distro.JAZZY: "uint16 NONE=0\nuint16 error_code\nstring error_msg\n",
}
_NAVIGATE_FEEDBACK = ("geometry_msgs/PoseStamped current_pose\n"
                      "builtin_interfaces/Duration navigation_time\n"
                      "builtin_interfaces/Duration estimated_time_remaining\n"
                      "int16 number_of_recoveries\nfloat32 distance_remaining\n")
_CANCEL_REQUEST = "action_msgs/GoalInfo goal_info\n"
_CANCEL_RESPONSE = ("int8 ERROR_NONE=0\nint8 ERROR_REJECTED=1\n"
                    "int8 ERROR_UNKNOWN_GOAL_ID=2\nint8 ERROR_GOAL_TERMINATED=3\n"
                    "int8 return_code\naction_msgs/GoalInfo[] goals_canceling\n")


def _action_definitions(action: str, goal: str, result: str, feedback: str
                        ) -> list[tuple[str, str]]:
    """The messages an action's goal, result and feedback give rise to (rosidl's Action)."""
    return [
        (f"{action}_Goal", goal),
        (f"{action}_Result", result),
        (f"{action}_Feedback", feedback),
        (f"{action}_SendGoal_Request",
         f"unique_identifier_msgs/UUID goal_id\n{action}_Goal goal\n"),
        (f"{action}_SendGoal_Response", "bool accepted\nbuiltin_interfaces/Time stamp\n"),
        (f"{action}_GetResult_Request", "unique_identifier_msgs/UUID goal_id\n"),
        (f"{action}_GetResult_Response", f"int8 status\n{action}_Result result\n"),
        (f"{action}_FeedbackMessage",
         f"unique_identifier_msgs/UUID goal_id\n{action}_Feedback feedback\n"),
    ]


def _service_descriptions(service: str) -> list[tuple[str, str]]:
    """What a service's type hash is computed over (rosidl's Service): its event message and
    the description with request_message, response_message and event_message."""
    return [
        (f"{service}_Event", f"service_msgs/ServiceEventInfo info\n"
                             f"{service}_Request[<=1] request\n"
                             f"{service}_Response[<=1] response\n"),
        (service, f"{service}_Request request_message\n{service}_Response response_message\n"
                  f"{service}_Event event_message\n"),
    ]


SERVICES = (f"{NAVIGATE_TO_POSE}_SendGoal", f"{NAVIGATE_TO_POSE}_GetResult", CANCEL_GOAL)
"""The services of the profile, by base type name."""


def _unnormalised(name: str) -> str:
    """rosbags' parser files every type under ``pkg/msg/``; services and actions keep their
    ``srv`` and ``action`` folders on the wire and in the hash."""
    for folder in ("srv", "action"):
        name = name.replace(f"/{folder}/msg/", f"/{folder}/")
    return name


def _renamed(definition: Any) -> Any:
    if isinstance(definition, tuple):
        if len(definition) == 2 and definition[0] == Nodetype.NAME \
                and isinstance(definition[1], str):
            return (Nodetype.NAME, _unnormalised(definition[1]))
        return tuple(_renamed(part) for part in definition)
    if isinstance(definition, list):
        return [_renamed(part) for part in definition]
    return definition


def _register(store: Typestore, definitions: list[tuple[str, str]]) -> None:
    types: dict[str, Any] = {}
    for name, text in definitions:
        types.update(get_types_from_msg(text, name))
    store.register({_unnormalised(name): _renamed(fields) for name, fields in types.items()})


def _definitions(distro: Distro) -> list[tuple[str, str]]:
    return [
        *_action_definitions(NAVIGATE_TO_POSE, _NAVIGATE_GOAL, _NAVIGATE_RESULT[distro],
                             _NAVIGATE_FEEDBACK),
        (f"{CANCEL_GOAL}_Request", _CANCEL_REQUEST),
        (f"{CANCEL_GOAL}_Response", _CANCEL_RESPONSE),
    ]


@cache
def typestore(distro: Distro) -> Typestore:
    """rosbags' store of ``distro`` with Nav2's NavigateToPose and CancelGoal registered
    (one per distribution and process: building it parses every definition)."""
    store = get_typestore(_STORES[distro])
    _register(store, _definitions(distro))
    return store


@cache
def _hash_store(distro: Distro) -> Typestore:
    store = get_typestore(_STORES[distro])
    # rosidl describes a .msg ``char`` as uint8 (see the module docstring); the store is a
    # private copy used for hashing only.
    for name, (constants, fields) in list(store.fielddefs.items()):
        store.fielddefs[name] = (constants, [
            (field, _char_as_uint8(definition)) for field, definition in fields])
    _register(store, _definitions(distro))
    for service in SERVICES:
        _register(store, _service_descriptions(service))
    return store


def _char_as_uint8(definition: Any) -> Any:
    if definition == (Nodetype.BASE, ("char", 0)):
        return (Nodetype.BASE, ("uint8", 0))
    if isinstance(definition, tuple):
        return tuple(_char_as_uint8(part) for part in definition)
    return definition


def type_hash(msgtype: str, distro: Distro) -> str:
    """The type hash rmw_zenoh_cpp of ``distro`` puts in key expressions and tokens for
    message, service or action-service type ``msgtype``."""
    if distro == Distro.HUMBLE:
        return HASH_NOT_SUPPORTED
    store = _hash_store(distro)
    if msgtype not in store.fielddefs:
        raise Ros2Error(f"type hash: no type description of '{msgtype}' (expected a type of "
                        f"the ROS 2 profile or of rosbags' {distro.value} store)")
    return store.hash_rihs01(msgtype)


def register_action(distro: Distro, action: str, goal: str, result: str, feedback: str
                    ) -> None:
    """Register an action's goal, result and feedback definitions (``.action`` thirds) and
    the services and message rosidl derives from them, for hashing and CDR."""
    definitions = _action_definitions(action, goal, result, feedback)
    for store in (typestore(distro), _hash_store(distro)):
        if f"{action}_Goal" not in store.fielddefs:
            _register(store, definitions)
    for service in (f"{action}_SendGoal", f"{action}_GetResult"):
        if service not in _hash_store(distro).fielddefs:
            _register(_hash_store(distro), _service_descriptions(service))


def register_service(distro: Distro, service: str, request: str, response: str) -> None:
    """Register a service's request and response definitions (``.srv`` halves) for hashing
    and CDR; for services beyond the profile's (tests pin rmw_zenoh's AddTwoInts example)."""
    definitions = [(f"{service}_Request", request), (f"{service}_Response", response)]
    for store in (typestore(distro), _hash_store(distro)):
        if f"{service}_Request" not in store.fielddefs:
            _register(store, definitions)
    if service not in _hash_store(distro).fielddefs:
        _register(_hash_store(distro), _service_descriptions(service))
