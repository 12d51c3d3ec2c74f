"""ROS 2 recordings REI did not make (a Gazebo run, a real robot) as REI's sample stream.

``BagSamples`` reads an MCAP file or a rosbag2 folder (any storage rosbags reads: mcap,
sqlite3; a ROS 1 bag too) with rosbags' ``AnyReader`` and turns its messages into the
``Sample`` stream of a ``.mission``'s room, so the same automata and requirements judge it:

- ground truth from /tf: ``map`` -> each body, matched to the room's bodies by the names
  REI's Gazebo generator gives its models (the robot's and every object's name, as in the
  .room); bodies never seen on /tf keep their declared pose (a static wall), but the robot
  and every moving object (dynamic objects, humans) must be there;
- the robot's belief from /odom, /scan (REP 117's +inf: no return) and /cmd_vel;
- the time from the message stamps (seconds from the robot's first /tf stamp);
- mission progress re-derived by REI's own ``MissionExecutor`` from the evidence: a task
  succeeds when Nav2's ``navigate_to_pose`` status says SUCCEEDED *and* the ground truth is
  within the goal's tolerances (else it fails, as a false claim), fails on ABORTED,
  CANCELED or its timeout; without Nav2's status topic, a task succeeds when the ground
  truth is within the goal's tolerances. After the last task the mission goes on for the
  .mission's settle period, as a live run does (a time limit reached then ends it as usual).

One sample per period of the mission's sample rate, at the stamp of the robot's ground
truth; the belief messages that arrive until the next one belong to it. A ``--map`` file
(``TopicMap``) renames topics and frames for other stacks.

Bad data never passes: a missing topic or frame is a ``BagError`` naming what was expected
and what the bag holds; gaps and rate drops, stamps going backwards, non-finite values and
scans whose header does not describe their ranges are collected as ``BagProblem``s (and
the truth's also reach the monitor as missing, out-of-order or non-finite samples), which
make the verdicts they could have passed inconclusive (``rei replay``). This module must
never import pybullet.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from rei.lang.suggest import did_you_mean
from rei.runtime.messages import (
    UNCOLLECTED,
    LaserScan,
    MissionEvent,
    NavState,
    RobotBelief,
    Sample,
)
from rei.runtime.messages.ros import (
    BELIEF_TOPICS,
    MAP,
    NAV2_STATUS,
    NAV2_STATUS_TOPIC,
    ROBOT_TOPICS,
    command_of,
    odometry_of,
    pose_of,
    scan_geometry_problem,
    scan_of,
    seconds,
)
from rei.runtime.observation.recordings.bag_evidence import NavEvidence, TopicRate
from rei.runtime.observation.recordings.bag_inputs import (
    MOVING_ROLES,
    BagError,
    BagProblem,
    BagWorld,
    TopicMap,
    load_topic_map,
)
from rei.runtime.simulation.mission import MissionExecutor

__all__ = ["BagError", "BagProblem", "BagSamples", "BagWorld", "TopicMap", "load_topic_map"]


class BagSamples(Iterator[Sample]):
    """The samples of a ROS 2 recording (see the module's docstring); after the last one,
    ``end()`` is (end time, outcome, reason) and ``problems`` what no verdict may pass on."""

    def __init__(self, path: Path, world: BagWorld, mapping: TopicMap | None = None) -> None:
        from rosbags.highlevel import AnyReader  # noqa: PLC0415  (heavy: only for bags)

        self.path = Path(path)
        self.world = world
        self.header = world.header
        self.mapping = mapping or TopicMap()
        self.problems: list[BagProblem] = []
        self.period = 1.0 / self.header.rate
        if not self.path.exists():
            raise BagError(f"{self.path}: expected a ROS 2 recording (an MCAP file or a "
                           f"rosbag2 folder), found nothing at that path")
        try:
            self._reader = AnyReader([self.path])
            self._reader.open()
        except Exception as exc:  # noqa: BLE001  (rosbags on a hostile file: any error)
            raise BagError(f"{self.path}: expected a ROS 2 recording rosbags can read (an "
                           f"MCAP file or a rosbag2 folder), found one it cannot: "
                           f"{_exception(exc)}") from None
        try:
            self._connections = self._check_topics()
        except BaseException:
            self.close()
            raise
        frame = self.mapping.frame
        self._names = {frame(o.name).lstrip("/"): i for i, o in enumerate(self.header.objects)}
        self._robot_frame = frame(self.header.robot.name).lstrip("/")
        self._map_frame = frame(MAP).lstrip("/")
        self._frames: set[tuple[str, str]] = set()
        self._poses = np.array(world.poses, dtype=np.float64).reshape(-1, 3)
        self._pose_times = np.full(len(self._poses), -math.inf)
        self._twists = np.zeros_like(self._poses)
        self._seen = np.zeros(len(self._poses), dtype=bool)
        self._robot: tuple[float, float, float] | None = None
        self._robot_time = -math.inf
        self._robot_twist = (0.0, 0.0, 0.0)
        self._odom = (UNCOLLECTED.odom, UNCOLLECTED.odom_twist)
        self._cmd = (0.0, 0.0)
        self._scan: LaserScan | None = None
        self._new_scan = False
        self._laser_min = math.inf
        self._rates: dict[str, TopicRate] = {}
        self._t0: float | None = None
        self._seq = -1
        self._executor = MissionExecutor(world.tasks, world.settle)
        self._goals = NavEvidence(NAV2_STATUS_TOPIC in self._connections)
        self._tolerances = {t.name: t.heading_tolerance for t in world.tasks}
        self._time_limit = self.header.mission_facts.time_limit \
            if self.header.mission_facts is not None else math.inf
        self._timed_out = False
        self._end: tuple[float, str, str] | None = None
        self._previous: float | None = None
        """The time of the latest sample in order."""
        self._end_reason = ""
        self._log_offset: float | None = None
        self._queue: list[tuple[float, int, str, Any]] = []
        self._count = 0
        self._samples = self._generate()

    # ---- the bag's topics -----------------------------------------------------------------

    def _check_topics(self) -> dict[str, list[Any]]:
        held: dict[str, list[Any]] = {}
        for c in self._reader.connections:
            held.setdefault(c.topic, []).append(c)
        holds = ", ".join(f"{t} ({held[t][0].msgtype})" for t in sorted(held)) or "no topics"
        wanted = {"/tf": True, "/tf_static": False, "/clock": False, NAV2_STATUS_TOPIC: False}
        for kind, topic in BELIEF_TOPICS.items():
            wanted[topic] = kind in self.header.data
        out: dict[str, list[Any]] = {}
        for topic, required in wanted.items():
            name = self.mapping.topic(topic)
            connections = held.get(name, [])
            expected = ROBOT_TOPICS[topic]
            if not connections:
                if required:
                    raise BagError(f"{self.path}: expected the topic {name} ({expected}"
                                   f"{', REI name ' + topic if name != topic else ''}), found "
                                   f"{holds}" + did_you_mean(name, list(held)))
                continue
            wrong = [c.msgtype for c in connections if c.msgtype != expected and
                     not (topic == "/cmd_vel" and c.msgtype == "geometry_msgs/msg/TwistStamped")]
            if wrong:
                raise BagError(f"{self.path}: topic {name}: expected the type {expected}, "
                               f"found {wrong[0]}")
            out[topic] = connections
        return out

    def _read(self) -> Iterator[tuple[str, int, Any]]:
        """(REI topic, log time in ns, decoded message) in the bag's order; undecodable
        messages are problems, never exceptions."""
        by_id = {c.id: topic for topic, cs in self._connections.items() for c in cs}
        connections = [c for cs in self._connections.values() for c in cs]
        try:
            for connection, log_time, raw in self._reader.messages(connections=connections):
                topic = by_id[connection.id]
                try:
                    message = self._reader.deserialize(raw, connection.msgtype)
                except Exception as exc:  # noqa: BLE001  (a damaged message: any error)
                    self._problem(topic, self._robot_time, f"a message cannot be decoded "
                                                           f"({_exception(exc)})")
                    continue
                yield topic, log_time, message
        except Exception as exc:  # noqa: BLE001  (rosbags on a damaged file)
            raise BagError(f"{self.path}: expected a readable ROS 2 recording, found damage "
                           f"after t={max(self._robot_time, 0.0):.3f} s: "
                           f"{_exception(exc)}") from None

    def _problem(self, topic: str, time: float, what: str) -> None:
        self.problems.append(BagProblem(self.mapping.topic(topic),
                                        time if math.isfinite(time) else 0.0, what))

    def _time(self, topic: str, stamp: Any) -> float:
        t = seconds(stamp)
        if self._t0 is None:
            self._t0 = t
        time = t - self._t0
        problem = self._rates.setdefault(topic, TopicRate()).see(time)
        if problem:
            self._problem(topic, time, problem)
        return time

    # ---- messages -------------------------------------------------------------------------

    def _robot_truth(self, item: Any, time: float) -> None:
        pose = pose_of(item.transform)
        if not all(map(math.isfinite, pose)):
            self._problem("/tf", time, f"a non-finite pose of {item.child_frame_id}")
        if self._robot is not None and time > self._robot_time:
            dt = time - self._robot_time
            px, py, pyaw = self._robot
            self._robot_twist = ((pose[0] - px) / dt, (pose[1] - py) / dt,
                                 math.remainder(pose[2] - pyaw, math.tau) / dt)
        self._robot, self._robot_time = pose, time

    def _object_truth(self, i: int, item: Any) -> None:
        pose = pose_of(item.transform)
        t = seconds(item.header.stamp) - (self._t0 or 0.0)
        if not all(map(math.isfinite, pose)):
            self._problem("/tf", t, f"a non-finite pose of {item.child_frame_id}")
        if self._seen[i] and t > self._pose_times[i]:
            dt = t - self._pose_times[i]
            old = self._poses[i]
            self._twists[i] = ((pose[0] - old[0]) / dt, (pose[1] - old[1]) / dt,
                               math.remainder(pose[2] - old[2], math.tau) / dt)
        self._poses[i] = pose
        self._pose_times[i] = t
        self._seen[i] = True

    def _stamped(self, topic: str, log_time: int, message: Any) -> float:
        """The time of a belief message: its stamp, else (a Twist, the action status, which
        carry none) its log time on the stamps' clock (offset at the first ground truth)."""
        stamp = getattr(getattr(message, "header", None), "stamp", None)
        if topic == "/clock":
            stamp = message.clock
        if stamp is not None:
            return self._time(topic, stamp)
        if self._log_offset is None:
            return self._robot_time if math.isfinite(self._robot_time) else 0.0
        time = log_time * 1e-9 - self._log_offset
        if topic != NAV2_STATUS_TOPIC:  # published on change, not at a rate: no gaps
            problem = self._rates.setdefault(topic, TopicRate()).see(time)
            if problem:
                self._problem(topic, time, problem)
        return time

    def _belief(self, topic: str, time: float, message: Any) -> None:
        if topic == "/odom":
            odom = odometry_of(message)
            if not all(map(math.isfinite, (*odom[0], *odom[1]))):
                self._problem(topic, time, "non-finite odometry")
            self._odom = odom
        elif topic == "/scan":
            problem = scan_geometry_problem(message)
            if problem:
                self._problem(topic, time, f"its header does not describe its ranges: "
                                           f"expected {problem}")
                return
            scan = scan_of(message)
            if np.count_nonzero(scan.ranges == -math.inf):
                self._problem(topic, time, "a range of -inf")
            self._scan, self._new_scan = scan, True
            finite = scan.ranges[np.isfinite(scan.ranges)]
            self._laser_min = float(finite.min()) if len(finite) else scan.range_max
        elif topic == "/cmd_vel":
            cmd = command_of(message)
            if not all(map(math.isfinite, cmd)):
                self._problem(topic, time, "a non-finite velocity command")
            self._cmd = cmd
        elif topic == NAV2_STATUS_TOPIC:
            for status in message.status_list:
                key = bytes(np.asarray(status.goal_info.goal_id.uuid, dtype=np.uint8))
                # STATUS_UNKNOWN (or a code action_msgs does not define) claims nothing:
                # the goal stays pending, never further on than the robot said
                self._goals.status(key, seconds(status.goal_info.stamp) - (self._t0 or 0.0),
                                   NAV2_STATUS.get(int(status.status), NavState.PENDING))

    def _heard(self, until: float) -> None:
        """Apply the belief messages stamped up to ``until``, in their stamps' order."""
        queue = self._queue
        while queue and queue[0][0] <= until + 1e-9:
            time, _, topic, message = heapq.heappop(queue)
            self._belief(topic, time, message)

    # ---- samples --------------------------------------------------------------------------

    def _generate(self) -> Iterator[Sample]:
        pending = False
        last = -math.inf
        for topic, log_time, message in self._read():
            if topic not in ("/tf", "/tf_static"):
                time = self._stamped(topic, log_time, message)
                if math.isfinite(time):
                    self._count += 1
                    heapq.heappush(self._queue, (time, self._count, topic, message))
                continue
            static = topic == "/tf_static"
            for item in message.transforms:
                parent = item.header.frame_id.lstrip("/")
                child = item.child_frame_id.lstrip("/")
                self._frames.add((parent, child))
                if parent != self._map_frame:
                    continue  # odom -> base_link and the like: not ground truth
                if child == self._robot_frame and not static:
                    time = self._time("/tf", item.header.stamp)
                    # one sample per period: faster ground truth (a Gazebo pose bridge at
                    # 50 Hz) is skipped until the next period begins
                    if pending and last <= time < last + self.period * (1 - 1e-6):
                        continue
                    if pending:
                        self._heard(self._robot_time)
                        yield self._sample()
                        if self._executor.finished:
                            self._finish()
                            return
                    if self._log_offset is None:
                        self._log_offset = log_time * 1e-9 - time
                    self._robot_truth(item, time)
                    last = time if math.isfinite(time) else last
                    pending = True
                elif child in self._names:
                    self._object_truth(self._names[child], item)
        if pending:
            self._heard(self._robot_time)
            yield self._sample(last=True)
        self._finish()

    def _sample(self, last: bool = False) -> Sample:
        """The sample at the robot's latest ground truth, with everything heard since."""
        assert self._robot is not None
        time = self._robot_time
        previous = self._previous
        # a sample period without the robot's ground truth is a lost sample (the monitor
        # counts it as missing: the requirements it could decide become inconclusive)
        step = 1
        if previous is not None and math.isfinite(time) and time > previous:
            step = max(1, round((time - previous) / self.period))
        self._seq += step
        events: list[MissionEvent] = []
        ordered = previous is None or (math.isfinite(time) and time > previous)
        if ordered and all(map(math.isfinite, self._robot)):
            self._previous = time
            self._goals.truth = self._robot
            running = self._executor.current_task
            if running is not None:
                self._goals.heading_tolerance = self._tolerances.get(running, 0.0)
            if time >= self._time_limit and self._executor.settling:
                # as the live run: the tasks are done, the time limit only cuts the settle
                # period short (an ordinary end, no timeout)
                events = self._executor.end_settled(time)
            elif time >= self._time_limit and not self._executor.finished:
                self._timed_out = True
                self._end_reason = f"mission time limit of {self._time_limit:g} s reached"
                events = self._executor.abandon(time, self._end_reason, self._robot)
            else:
                events = self._executor.tick(time, self._goals, self._robot)
                if self._executor.current_task is not None:
                    self._goals.heading_tolerance = self._tolerances.get(
                        self._executor.current_task, 0.0)
            if last and not self._executor.finished:
                self._timed_out = True
                self._end_reason = f"the recording ends at t={time:g} s, before the mission's end"
                events += self._executor.abandon(time, self._end_reason, self._robot, cause="cut")
        data = self.header.data
        odom, odom_twist = self._odom if "odometry" in data else \
            (UNCOLLECTED.odom, UNCOLLECTED.odom_twist)
        scan = self._scan if self._new_scan and "laser" in data else None
        if "laser" not in data:
            laser_min = UNCOLLECTED.laser_min
        elif math.isfinite(self._laser_min):
            laser_min = self._laser_min
        else:
            laser_min = self._scan.range_max if self._scan is not None else 0.0
        collects_nav = "nav_state" in data
        nav = self._goals.feedback().state if collects_nav else UNCOLLECTED.nav_state
        task = self._executor.current_task if collects_nav else None
        cmd = self._cmd if collects_nav else UNCOLLECTED.cmd
        self._new_scan = False
        return Sample(self._seq, time, self._robot, self._robot_twist, self._poses.copy(),
                      self._twists.copy(),
                      RobotBelief(odom, odom_twist, laser_min, scan, nav, task, cmd),
                      tuple(events) if "mission_events" in data else ())

    def _finish(self) -> None:
        self.close()
        if self._robot is None:
            pairs = sorted(f"{p} -> {c}" for p, c in self._frames)
            found = ", ".join(pairs[:20]) + (f" (and {len(pairs) - 20} more)"
                                             if len(pairs) > 20 else "") or "none"
            raise BagError(f"{self.path}: expected /tf transforms {self._map_frame} -> "
                           f"{self._robot_frame} (the robot's ground truth), found the frames: "
                           f"{found}")
        moving = [o.name for i, o in enumerate(self.header.objects)
                  if o.role in MOVING_ROLES and not self._seen[i]]
        if moving:
            raise BagError(f"{self.path}: expected /tf transforms {self._map_frame} -> "
                           f"{self.mapping.frame(moving[0])} (the ground truth of the "
                           f"{next(o.role for o in self.header.objects if o.name == moving[0])}"
                           f" '{moving[0]}' of the room), found none"
                           + did_you_mean(self.mapping.frame(moving[0]),
                                          sorted({c for _, c in self._frames})))
        results = self._executor.results
        failed = [r for r in results if not r.succeeded]
        end = self._previous or 0.0
        if self._timed_out:
            self._end = (end, "timeout", self._end_reason)
        else:
            self._end = (end, "failed" if failed else "completed",
                         f"{len(failed)} of {len(results)} tasks failed" if failed
                         else f"all {len(results)} tasks succeeded")

    def __next__(self) -> Sample:
        return next(self._samples)

    def end(self) -> tuple[float, str, str] | None:
        """(end time, outcome, reason) once every sample was read."""
        return self._end

    def close(self) -> None:
        try:
            self._reader.close()
        except Exception:  # noqa: BLE001, S110  (closing a damaged bag: nothing to save)
            pass


def _exception(exc: BaseException) -> str:
    return f"{type(exc).__name__}{': ' + str(exc) if str(exc) else ''}"
