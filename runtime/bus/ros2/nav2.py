"""A client of Nav2's ``navigate_to_pose`` action over rmw_zenoh, and its goal state machine.

A ROS 2 action is no rmw entity (ros2/rmw_zenoh docs/design.md, "Actions"): rcl_action
builds it from three services and two topics under ``<action>/_action/``: ``send_goal``,
``cancel_goal`` and ``get_result`` (services of the types rosidl derives, see ``types``),
``feedback`` and ``status`` (``action_msgs/msg/GoalStatusArray``, transient local, depth 1).
``NavigateToPoseClient`` declares them as rclcpp's action client does and keeps one goal's
state, fed from whatever thread Zenoh answers on; ``snapshot()`` reads it as REI's
``GoalFeedback`` (the goal states of thesis Figure 22 are actionlib's, which ROS 2 kept):

=====================================  ================================================
action_msgs/GoalStatus                 REI NavState
=====================================  ================================================
goal sent, no answer yet               PENDING
accepted (1), executing (2)            ACTIVE
canceling (3)                          ACTIVE
succeeded (4)                          SUCCEEDED
canceled (5), or cancelled by REI      PREEMPTED (at once when REI cancels)
aborted (6), rejected, no server       ABORTED (with the reason)
=====================================  ================================================

This module must never import the simulation; it blocks a caller at most the wait it is
given (a goal's acceptance, a cancel's answer), never for a goal's result.
"""

from __future__ import annotations

import hashlib
import math
import threading
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from rei.runtime.bus.ros2.attachment import Attachment
from rei.runtime.bus.ros2.names import DEFAULT_QOS, LATCHED_QOS, Distro, EntityKind
from rei.runtime.bus.ros2.node import RmwNode
from rei.runtime.bus.ros2.types import CANCEL_GOAL, GOAL_STATUS_ARRAY, NAVIGATE_TO_POSE
from rei.runtime.messages import NavState
from rei.runtime.messages.ros import NAV2_STATUS, yaw_quaternion
from rei.runtime.robot.contract import GoalFeedback, NavGoal

ACTION = "navigate_to_pose"
"""Nav2's bt_navigator serves this action name (relative: it lives in the robot's namespace)."""

_TERMINAL = frozenset({NavState.SUCCEEDED, NavState.ABORTED, NavState.PREEMPTED})


def goal_uuid(seed: int, index: int) -> bytes:
    """A goal id that is the same for the same run (seed, goal number): reruns match."""
    return hashlib.blake2b(f"rei-goal/{seed}/{index}".encode(), digest_size=16).digest()


def _state(code: int) -> NavState | None:
    """The navigation state a GoalStatus code reports to REI's robot contract (the shared
    ROS 2 mapping), or None for STATUS_UNKNOWN and undefined codes. A goal the server has
    accepted is ACTIVE for the mission (as ``_on_accept`` says): the server has it."""
    state = NAV2_STATUS.get(code)
    return NavState.ACTIVE if state == NavState.PENDING else state


@dataclass
class _Goal:
    name: str
    uuid: bytes
    sent_at: float
    """Wall clock (monotonic) when the goal was sent: an unanswered goal ages out."""
    state: NavState = NavState.PENDING
    message: str = ""
    distance: float | None = None


class NavigateToPoseClient:
    """One navigation goal at a time through Nav2's action, as rclcpp_action's client."""

    def __init__(self, node: RmwNode, *, frame: str = "map", server_wait: float = 10.0,
                 seed: int = 0) -> None:
        self._node, self._frame, self._server_wait, self._seed = node, frame, server_wait, seed
        base = f"{ACTION}/_action"
        self._send = node.client(f"{base}/send_goal", f"{NAVIGATE_TO_POSE}_SendGoal")
        self._cancel = node.client(f"{base}/cancel_goal", CANCEL_GOAL)
        self._result = node.client(f"{base}/get_result", f"{NAVIGATE_TO_POSE}_GetResult")
        self.feedback_sub = node.subscription(f"{base}/feedback",
                                              f"{NAVIGATE_TO_POSE}_FeedbackMessage",
                                              self._on_feedback, DEFAULT_QOS)
        self.status_sub = node.subscription(f"{base}/status", GOAL_STATUS_ARRAY,
                                            self._on_status, LATCHED_QOS)
        self._lock = threading.Lock()
        self._goal: _Goal | None = None
        self._count = 0
        t = node.store.types
        self._uuid_t = t["unique_identifier_msgs/msg/UUID"]
        self._time_t = t["builtin_interfaces/msg/Time"]

    # ---- goals ----------------------------------------------------------------------------

    def send(self, goal: NavGoal, stamp_ns: int, wait: float = 0.0) -> None:
        """Send ``goal`` (preempting the current one) and wait at most ``wait`` wall seconds
        for the server to answer, so a stack that answers in time knows the goal before
        simulated time moves on (a later answer is taken when it comes)."""
        with self._lock:
            previous = self._goal
            self._count += 1
            current = _Goal(goal.name, goal_uuid(self._seed, self._count), time.monotonic())
            self._goal = current
        if previous is not None and previous.state not in _TERMINAL:
            previous.state = NavState.PREEMPTED  # a new goal preempts (nobody reads it now)
            self._request_cancel(previous.uuid, wait)
        t = self._node.store.types
        x, y, z, w = yaw_quaternion(goal.yaw if goal.yaw is not None else 0.0)
        pose = t["geometry_msgs/msg/PoseStamped"](
            t["std_msgs/msg/Header"](self._time_t(stamp_ns // 10**9, stamp_ns % 10**9),
                                     self._frame),
            t["geometry_msgs/msg/Pose"](t["geometry_msgs/msg/Point"](goal.x, goal.y, 0.0),
                                        t["geometry_msgs/msg/Quaternion"](x, y, z, w)))
        request = t[f"{NAVIGATE_TO_POSE}_SendGoal_Request"](
            self._uuid(current.uuid), t[f"{NAVIGATE_TO_POSE}_Goal"](pose, ""))
        answered = threading.Event()

        def accepted(response: Any) -> None:
            self._on_accept(current, response)
            answered.set()

        def failed(error: str) -> None:
            self._end(current, NavState.ABORTED, f"send_goal failed: {error}")
            answered.set()

        self._send.call_async(request, accepted, failed)
        if wait > 0:
            answered.wait(wait)

    def cancel(self, wait: float = 0.0) -> None:
        """Cancel the running goal: PREEMPTED at once (REI's contract: the caller decided),
        and the server is asked to cancel it too."""
        with self._lock:
            goal = self._goal
            running = goal is not None and goal.state not in _TERMINAL
            if goal is not None and running:
                goal.state, goal.message = NavState.PREEMPTED, "cancelled"
        if goal is not None and running:
            self._request_cancel(goal.uuid, wait)

    def snapshot(self) -> GoalFeedback:
        """The current goal's state as REI's GoalFeedback (a goal nobody answered within the
        server wait is aborted here, saying what to check)."""
        with self._lock:
            goal = self._goal
            if goal is None:
                return GoalFeedback(NavState.IDLE, None)
            unanswered = goal.state == NavState.PENDING \
                and time.monotonic() - goal.sent_at > self._server_wait
        if unanswered:
            reason = self._why_unanswered()  # asks the graph: outside the lock
            with self._lock:
                if goal.state == NavState.PENDING:
                    goal.state, goal.message = NavState.ABORTED, reason
        with self._lock:
            return GoalFeedback(goal.state, goal.name, goal.distance, goal.message)

    def _why_unanswered(self) -> str:
        """Why no server answered, as far as the ROS graph's liveliness tokens tell: a server
        of another type hash is a distribution mismatch (humble vs jazzy)."""
        said = (f"no {ACTION} action server accepted the goal within {self._server_wait:g} s")
        servers = [t for t in self._node.graph(timeout=0.5)
                   if t.kind == EntityKind.SERVICE and t.topic == self._send.token.topic]
        if not servers:
            return (f"{said} (no such server in the ROS graph of domain {self._node.domain}: "
                    f"is Nav2 running with RMW_IMPLEMENTATION=rmw_zenoh_cpp and ROS_DOMAIN_ID="
                    f"{self._node.domain}, connected to REI's router?)")
        theirs = servers[0]
        if theirs.type_hash != self._send.token.type_hash:
            return (f"{said}: node {theirs.node_name} serves {theirs.topic} with type hash "
                    f"{theirs.type_hash}, REI speaks {self._send.token.type_hash} (is the "
                    f"distro option the stack's: humble writes TypeHashNotSupported, jazzy "
                    f"RIHS01?)")
        return f"{said} (node {theirs.node_name} serves {theirs.topic} but did not answer)"

    # ---- answers (Zenoh's threads) --------------------------------------------------------

    def _uuid(self, raw: bytes) -> Any:
        return self._uuid_t(np.frombuffer(raw, dtype=np.uint8).copy())

    def _request_cancel(self, uuid: bytes, wait: float) -> None:
        t = self._node.store.types
        request = t[f"{CANCEL_GOAL}_Request"](
            t["action_msgs/msg/GoalInfo"](self._uuid(uuid), self._time_t(0, 0)))
        answered = threading.Event()
        self._cancel.call_async(request, lambda response: answered.set(),
                                lambda error: answered.set())
        if wait > 0:
            answered.wait(wait)

    def _end(self, goal: _Goal, state: NavState, message: str) -> None:
        with self._lock:
            if goal.state not in _TERMINAL:
                goal.state, goal.message = state, message

    def _on_accept(self, goal: _Goal, response: Any) -> None:
        if not response.accepted:
            self._end(goal, NavState.ABORTED, f"{ACTION} rejected the goal")
            return
        with self._lock:
            if goal.state == NavState.PENDING:
                goal.state = NavState.ACTIVE
        request = self._node.store.types[f"{NAVIGATE_TO_POSE}_GetResult_Request"](
            self._uuid(goal.uuid))
        self._result.call_async(request, lambda result: self._on_result(goal, result),
                                lambda error: self._end(goal, NavState.ABORTED,
                                                        f"get_result failed: {error}"))

    def _on_result(self, goal: _Goal, response: Any) -> None:
        state = _state(int(response.status))
        if state is None or state not in _TERMINAL:
            self._end(goal, NavState.ABORTED, f"get_result answered status {response.status}")
            return
        self._end(goal, state, _reason(response.result, state, self._node.distro))

    def _on_status(self, message: Any, _: Attachment) -> None:
        with self._lock:
            goal = self._goal
            if goal is None:
                return
            for status in message.status_list:
                if bytes(status.goal_info.goal_id.uuid) != goal.uuid:
                    continue
                state = _state(int(status.status))
                if state is None or goal.state in _TERMINAL:
                    continue
                if state in _TERMINAL:
                    goal.state = state
                    if state == NavState.ABORTED:
                        goal.message = f"{ACTION} aborted the goal"
                elif goal.state == NavState.PENDING:
                    goal.state = state

    def _on_feedback(self, message: Any, _: Attachment) -> None:
        distance = float(message.feedback.distance_remaining)
        with self._lock:
            goal = self._goal
            if goal is not None and bytes(message.goal_id.uuid) == goal.uuid \
                    and math.isfinite(distance) and distance >= 0:
                goal.distance = distance


def _reason(result: Any, state: NavState, distro: Distro) -> str:
    if state != NavState.ABORTED:
        return ""
    if distro == Distro.HUMBLE:
        return f"{ACTION} aborted the goal"
    return f"{ACTION} aborted the goal: error {result.error_code} {result.error_msg}".strip()
