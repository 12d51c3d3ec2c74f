"""The ROS 2 robot adapter: a ROS 2 stack (e.g. Nav2) on rmw_zenoh as REI's robot under test.

``Ros2Controller`` implements REI's robot contract (``rei.runtime.robot.contract.Controller``)
by talking to a ROS 2 graph over a Zenoh router, with no ROS on REI's side
(``rei run --controller ros2:router=tcp/127.0.0.1:7447,...``; ``parse_options`` reads the
options). Per control tick (``step``), at the observation's simulated time, it publishes

- ``/clock`` (rosgraph_msgs/Clock): the stack runs with ``use_sim_time:=true``;
- ``odom`` (nav_msgs/Odometry, ``odom`` -> ``base_link``) and ``tf`` (the same transform);
- ``scan`` (sensor_msgs/LaserScan in the laser's frame) when the laser measured anew;
- once, ``tf_static`` (``base_link`` -> laser at its mount; ``map`` -> ``odom`` identity
  unless ``map-odom=off``: REI's odometry is expressed in the world frame, where it starts at
  the true start pose, so the two frames coincide until odometry drifts);

then waits at most ``cmd-wait`` wall seconds for a ``cmd_vel`` (geometry_msgs/Twist) that
arrives after those messages, and answers the latest one. The timing model, honestly: a
ROS 2 stack is not lock-stepped with REI. Its timers run on /clock, so it computes when the
clock moves, and REI gives it up to ``cmd-wait`` per tick to answer; an answer that comes
later is used at the next tick. The latest command is held, as a real base holds it, for
``cmd-timeout`` simulated seconds, after which the base stops (a base's command watchdog).
A goal and a cancel are given the same ``cmd-wait`` for the server's answer, so a stack that
answers in time knows them before simulated time moves on; the goal's state is read as it
stood when a tick began (the stack's answer to a tick counts at the next). So a run with a
ROS stack depends on wall-clock timing: it repeats exactly only while the stack answers
within the waits, unlike a Python controller's run; the verdict is still REI's, from its own
ground truth.

Goals go to Nav2's ``navigate_to_pose`` action (``nav2.NavigateToPoseClient``), or with
``goals=topic`` as a geometry_msgs/PoseStamped on ``goal_pose`` (what RViz's "2D Goal Pose"
sends and Nav2's bt_navigator subscribes): there is no answer on that topic, so the adapter
reports the goal active until its *odometry* is within the goal's tolerance (and heading),
and succeeded then -- the robot's own claim, which REI's verdict checks against ground truth.

This module must never import pybullet: the adapter sees only what the robot's sensors say.
"""

from __future__ import annotations

import math
import os
import threading
import time
from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np

from rei.lang.suggest import did_you_mean
from rei.runtime.bus.ros2.attachment import Attachment
from rei.runtime.bus.ros2.errors import Ros2Error
from rei.runtime.bus.ros2.names import (
    DEFAULT_QOS,
    LATCHED_QOS,
    SENSOR_QOS,
    Distro,
    check_namespace,
    check_node_name,
)
from rei.runtime.bus.ros2.nav2 import NavigateToPoseClient
from rei.runtime.bus.ros2.node import Publisher, RmwNode, client_config, import_zenoh
from rei.runtime.bus.ros2.types import CLOCK, POSE_STAMPED
from rei.runtime.messages import NavState
from rei.runtime.messages.ros import (
    ODOMETRY,
    SCAN,
    TF,
    TOPICS,
    TWIST,
    command_of,
    ros_ranges,
    stamp_ns,
    yaw_quaternion,
)
from rei.runtime.robot.contract import (
    STOP,
    ControllerContext,
    GoalFeedback,
    NavGoal,
    Observation,
    VelocityCommand,
)


@dataclass(frozen=True)
class Ros2Options:
    """How REI reaches the ROS 2 stack (``ros2:key=value,...`` on ``--controller``)."""

    router: str = "tcp/127.0.0.1:7447"
    """The Zenoh router REI and the stack both connect to (`rei bus` prints it)."""
    domain: int = 0
    """ROS_DOMAIN_ID of the stack (default: this environment's ROS_DOMAIN_ID, else 0)."""
    namespace: str = "/"
    """The robot's ROS namespace (relative topics and the action live under it)."""
    distro: Distro = Distro.JAZZY
    """humble: type hashes 'TypeHashNotSupported'; jazzy (and kilted): RIHS01."""
    cmd_wait: float = 0.2
    """Wall seconds to wait per tick for a fresh cmd_vel (0: never wait)."""
    cmd_timeout: float = 0.5
    """Simulated seconds a cmd_vel is held before the base stops."""
    goals: str = "action"
    """'action' (Nav2's navigate_to_pose) or 'topic' (PoseStamped on goal_pose)."""
    server_wait: float = 10.0
    """Wall seconds a goal may stay unanswered before it is aborted (no action server)."""
    map_odom: bool = True
    """Publish map -> odom as a static identity (off when the stack localises itself)."""
    node: str = "rei_sim"
    """The ROS node name REI's side appears as."""
    odom_frame: str = "odom"
    base_frame: str = "base_link"
    laser_frame: str = "base_scan"
    credentials: str | None = None
    """The folder `rei bus` printed (or the simulation role's file in it): REI's side joins
    as the simulation role (default: $REI_BUS_CREDENTIALS when set, else no authentication)."""
    zenoh_config: str | None = None
    """A Zenoh JSON5 configuration file to start from (TLS, timeouts, ...)."""


_KEYS = {f.name.replace("_", "-"): f.name for f in fields(Ros2Options)}


def parse_options(text: str, environ: dict[str, str] | None = None) -> Ros2Options:
    """``key=value,key=value`` (the part after ``ros2:``) as Ros2Options; Ros2Error naming
    the key, what was expected and what was found."""
    env = os.environ if environ is None else environ
    options = Ros2Options()
    if env.get("ROS_DOMAIN_ID", "").strip():
        options = replace(options, domain=_domain(env["ROS_DOMAIN_ID"].strip(),
                                                  "ROS_DOMAIN_ID"))
    if not text:
        return options
    values: dict[str, Any] = {}
    for item in text.split(","):
        key, sep, value = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise Ros2Error(f"--controller ros2: expected key=value, found '{item}'")
        name = _KEYS.get(key)
        if name is None:
            raise Ros2Error(f"--controller ros2: unknown option '{key}', expected one of "
                            f"{', '.join(sorted(_KEYS))}" + did_you_mean(key, list(_KEYS)))
        values[name] = _value(name, key, value.strip())
    options = replace(options, **values)
    check_namespace(options.namespace)
    check_node_name(options.node)
    return options


def _domain(value: str, where: str) -> int:
    if not value.isdigit() or not 0 <= int(value) <= 232:
        raise Ros2Error(f"{where}: expected a ROS domain id 0..232, found '{value}'")
    return int(value)


def _value(name: str, key: str, value: str) -> Any:
    where = f"--controller ros2: {key}"
    if name == "domain":
        return _domain(value, where)
    if name == "distro":
        try:
            return Distro(value)
        except ValueError:
            raise Ros2Error(f"{where}: expected one of {', '.join(d.value for d in Distro)}, "
                            f"found '{value}'") from None
    if name in ("cmd_wait", "cmd_timeout", "server_wait"):
        try:
            number = float(value)
        except ValueError:
            number = math.nan
        if not math.isfinite(number) or number < 0:
            raise Ros2Error(f"{where}: expected seconds >= 0, found '{value}'")
        return number
    if name == "goals":
        if value not in ("action", "topic"):
            raise Ros2Error(f"{where}: expected action or topic, found '{value}'")
        return value
    if name == "map_odom":
        if value not in ("on", "off"):
            raise Ros2Error(f"{where}: expected on or off, found '{value}'")
        return value == "on"
    if not value:
        raise Ros2Error(f"{where}: expected a value, found nothing")
    return value


def _credentials(given: str | None) -> dict[str, Any] | None:
    """The simulation role's credentials from `rei bus`'s folder, or None (no auth)."""
    from pathlib import Path  # noqa: PLC0415

    from rei.runtime.bus.client import CREDENTIALS_ENV, read_credentials  # noqa: PLC0415
    from rei.runtime.bus.errors import BusError  # noqa: PLC0415
    where = given or os.environ.get(CREDENTIALS_ENV)
    if not where:
        return None
    try:
        return read_credentials("simulation", Path(where))
    except BusError as exc:
        raise Ros2Error(f"--controller ros2: credentials: {exc}") from None


def _topic(absolute: str) -> str:
    """A robot-facing topic of the shared mapping, relative so it follows the namespace."""
    return absolute.lstrip("/")


class Ros2Controller:
    """REI's robot under test, played by a ROS 2 stack on the other side of a Zenoh router."""

    name = "ros2"

    def __init__(self, options: Ros2Options | None = None) -> None:
        self.options = options or Ros2Options()
        self._session: Any = None
        self._node: RmwNode | None = None
        self._lock = threading.Condition()
        self._cmd: VelocityCommand = STOP
        self._cmd_count = 0
        self._cmd_sim_time = -math.inf
        self._sim_time = 0.0
        self._scan_time: float | None = None
        self._feedback = GoalFeedback(NavState.IDLE, None)
        self._goal: NavGoal | None = None
        self._topic_goal_state = NavState.IDLE
        self._static_sent = False
        self._action: NavigateToPoseClient | None = None
        self._goal_pub: Publisher | None = None
        self._bad_cmd = ""
        self._waits_missed = 0
        """Ticks whose cmd_vel did not come within cmd-wait (for the docs' timing model)."""

    # ---- set-up ---------------------------------------------------------------------------

    def reset(self, context: ControllerContext) -> None:
        self.close()
        zenoh = import_zenoh()
        o = self.options
        secret = _credentials(o.credentials)
        try:
            self._session = zenoh.open(client_config(o.router, o.zenoh_config, secret))
        except Ros2Error:
            raise
        except Exception as exc:  # noqa: BLE001  (zenoh says why it could not connect)
            who = f" as {secret['user']}" if secret else ""
            raise Ros2Error(f"--controller ros2: cannot join the Zenoh router at {o.router}"
                            f"{who}: {exc} (start one with `rei bus` and give router=... and "
                            f"credentials=...)") from None
        node = RmwNode(self._session, o.node, namespace=o.namespace, domain=o.domain,
                       distro=o.distro)
        self._node, self._context = node, context
        self._clock = node.publisher("/clock", CLOCK, DEFAULT_QOS)
        self._odom = node.publisher(_topic("/odom"), TOPICS["/odom"], DEFAULT_QOS)
        self._tf = node.publisher(_topic("/tf"), TOPICS["/tf"], DEFAULT_QOS)
        self._tf_static = node.publisher(_topic("/tf_static"), TOPICS["/tf_static"],
                                         LATCHED_QOS)
        self._scan = node.publisher(_topic("/scan"), SCAN, SENSOR_QOS)
        self.cmd_sub = node.subscription(_topic("/cmd_vel"), TWIST, self._on_cmd, DEFAULT_QOS)
        if o.goals == "action":
            self._action = NavigateToPoseClient(node, server_wait=o.server_wait,
                                                seed=context.seed)
            self._goal_pub = None
        else:
            self._action = None
            self._goal_pub = node.publisher("goal_pose", POSE_STAMPED, DEFAULT_QOS)
        self._cmd, self._cmd_count, self._cmd_sim_time = STOP, 0, -math.inf
        self._bad_cmd = ""
        self._sim_time, self._scan_time, self._static_sent = 0.0, None, False
        self._feedback, self._goal = GoalFeedback(NavState.IDLE, None), None
        self._topic_goal_state = NavState.IDLE
        t = node.store.types
        self._types = t
        self._time_t, self._header_t = t["builtin_interfaces/msg/Time"], t["std_msgs/msg/Header"]

    def close(self) -> None:
        """Leave the ROS graph and close the session (a new ``reset`` does it first; the
        robot's host process ends with the run, which closes it all the same)."""
        if self._node is not None:
            self._node.close()
            self._node = None
        if self._session is not None:
            try:
                self._session.close()
            except Exception:  # noqa: BLE001,S110  (already closed with the router)
                pass
            self._session = None

    # ---- goals ----------------------------------------------------------------------------

    def send_goal(self, goal: NavGoal) -> None:
        if self._node is None:
            raise Ros2Error("ros2 controller: send_goal() before reset()")
        self._goal = goal
        if self._action is not None:
            self._action.send(goal, stamp_ns(self._sim_time), self.options.cmd_wait)
            self._feedback = self._action.snapshot()
            return
        assert self._goal_pub is not None
        self._goal_pub.publish(self._pose(goal))
        self._topic_goal_state = NavState.ACTIVE
        self._feedback = GoalFeedback(NavState.ACTIVE, goal.name)

    def cancel_goal(self) -> None:
        if self._action is not None:
            self._action.cancel(self.options.cmd_wait)
            self._feedback = self._action.snapshot()
        elif self._topic_goal_state in (NavState.PENDING, NavState.ACTIVE):
            self._topic_goal_state = NavState.PREEMPTED
            self._feedback = GoalFeedback(NavState.PREEMPTED, self._goal.name
                                          if self._goal else None, None, "cancelled")

    def feedback(self) -> GoalFeedback:
        return self._feedback

    # ---- the tick -------------------------------------------------------------------------

    def step(self, observation: Observation) -> VelocityCommand:
        if self._node is None:
            raise Ros2Error("ros2 controller: step() before reset()")
        now = observation.time
        self._sim_time = now
        # The goal's state as the stack had told it when this tick began: what it says in
        # answer to this tick's messages (a status beside the cmd_vel, on another thread)
        # counts at the next tick, so the order of two callbacks never decides a run.
        self._feedback = self._goal_feedback(observation)
        with self._lock:
            seen = self._cmd_count
        self._publish_sensors(observation)
        if self.options.cmd_wait > 0:
            deadline = time.monotonic() + self.options.cmd_wait
            with self._lock:
                while self._cmd_count == seen:
                    left = deadline - time.monotonic()
                    if left <= 0:
                        self._waits_missed += 1
                        break
                    self._lock.wait(left)
        with self._lock:
            if self._bad_cmd:
                raise Ros2Error(self._bad_cmd)
            fresh = now - self._cmd_sim_time <= self.options.cmd_timeout
            command = self._cmd if fresh else STOP
        return command

    def _goal_feedback(self, observation: Observation) -> GoalFeedback:
        if self._action is not None:
            return self._action.snapshot()
        goal = self._goal
        if goal is None or self._topic_goal_state != NavState.ACTIVE:
            return self._feedback
        x, y, yaw = observation.odom_pose
        distance = math.hypot(goal.x - x, goal.y - y)
        heading_ok = goal.yaw is None or abs(
            math.remainder(goal.yaw - yaw, math.tau)) <= 0.1
        if distance <= goal.tolerance and heading_ok:
            self._topic_goal_state = NavState.SUCCEEDED
            return GoalFeedback(NavState.SUCCEEDED, goal.name, distance,
                                "odometry within the goal's tolerance")
        return GoalFeedback(NavState.ACTIVE, goal.name, distance)

    def _on_cmd(self, message: Any, _: Attachment) -> None:
        command = VelocityCommand(*command_of(message))
        if not command.finite:
            # rejected at the edge, and the run ends as an error saying so (a stack that
            # sends NaN now and then must not drive on its last good command to a pass)
            with self._lock:
                self._bad_cmd = (f"the ROS 2 stack published a non-finite cmd_vel (linear.x "
                                 f"{command.linear}, angular.z {command.angular}) at simulated "
                                 f"time {self._sim_time:g} s")
                self._cmd_count += 1
                self._lock.notify_all()
            return
        with self._lock:
            self._cmd, self._cmd_sim_time = command, self._sim_time
            self._cmd_count += 1
            self._lock.notify_all()

    # ---- messages -------------------------------------------------------------------------

    def _header(self, time_s: float, frame: str) -> Any:
        ns = stamp_ns(time_s)
        return self._header_t(self._time_t(ns // 10**9, ns % 10**9), frame)

    def _transform(self, time_s: float, parent: str, child: str, x: float, y: float,
                   z: float, yaw: float) -> Any:
        t = self._types
        return t["geometry_msgs/msg/TransformStamped"](
            self._header(time_s, parent), child,
            t["geometry_msgs/msg/Transform"](t["geometry_msgs/msg/Vector3"](x, y, z),
                                             t["geometry_msgs/msg/Quaternion"](
                                                 *yaw_quaternion(yaw))))

    def _pose(self, goal: NavGoal) -> Any:
        t = self._types
        return t[POSE_STAMPED](self._header(self._sim_time, "map"), t["geometry_msgs/msg/Pose"](
            t["geometry_msgs/msg/Point"](goal.x, goal.y, 0.0),
            t["geometry_msgs/msg/Quaternion"](*yaw_quaternion(goal.yaw or 0.0))))

    def _publish_sensors(self, observation: Observation) -> None:
        t, o, now = self._types, self.options, observation.time
        ns = stamp_ns(now)
        self._clock.publish(t[CLOCK](self._time_t(ns // 10**9, ns % 10**9)))
        if not self._static_sent:
            laser = self._context.laser
            items = [self._transform(now, o.base_frame, o.laser_frame, laser.mount_x,
                                     laser.mount_y, laser.mount_z, 0.0)]
            if o.map_odom:
                items.append(self._transform(now, "map", o.odom_frame, 0.0, 0.0, 0.0, 0.0))
            self._tf_static.publish(t[TF](items))
            self._static_sent = True
        x, y, yaw = observation.odom_pose
        linear, angular = observation.odom_twist
        covariance = np.zeros(36, dtype=np.float64)
        vector, point = t["geometry_msgs/msg/Vector3"], t["geometry_msgs/msg/Point"]
        self._odom.publish(t[ODOMETRY](
            self._header(now, o.odom_frame), o.base_frame,
            t["geometry_msgs/msg/PoseWithCovariance"](
                t["geometry_msgs/msg/Pose"](point(x, y, 0.0), t["geometry_msgs/msg/Quaternion"](
                    *yaw_quaternion(yaw))), covariance),
            t["geometry_msgs/msg/TwistWithCovariance"](
                t["geometry_msgs/msg/Twist"](vector(linear, 0.0, 0.0),
                                             vector(0.0, 0.0, angular)), covariance)))
        self._tf.publish(t[TF]([self._transform(now, o.odom_frame, o.base_frame, x, y, 0.0,
                                                yaw)]))
        scan = observation.scan
        if scan is not None and observation.scan_time != self._scan_time:
            self._scan_time = observation.scan_time
            stamp = now if observation.scan_time is None else observation.scan_time
            # REP 117: a beam without a return is +inf (REI's laser reports range_max),
            # so a costmap never marks an obstacle where nothing was hit
            ranges = ros_ranges(scan)
            angle_max = scan.angle_min + scan.angle_increment * (len(ranges) - 1)
            self._scan.publish(t[SCAN](
                self._header(stamp, o.laser_frame), scan.angle_min, angle_max,
                scan.angle_increment, 0.0, 1.0 / self._context.laser.rate, scan.range_min,
                scan.range_max, ranges, np.zeros(0, dtype=np.float32)))
