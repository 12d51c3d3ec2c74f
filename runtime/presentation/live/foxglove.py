"""A Foxglove WebSocket server showing a run live, on the channels of its MCAP recording.

``FoxgloveView`` is a ``View``: it opens a Foxglove WebSocket server (foxglove-sdk, the
``watch`` extra) on 127.0.0.1 and logs each frame's sample on the channels `rei run
--record` writes (``rei.runtime.messages.ros``: /tf, /tf_static, /scan, /odom, /cmd_vel,
/world/markers, /rei/events, /rei/signals, in ROS 2 types and CDR, plus the exact trace on
/rei/trace), so Foxglove shows a run live as it shows its recording. Two channels more show
the paths: /rei/path (nav_msgs/Path, the robot's ground-truth route so far) and /rei/goals
(nav_msgs/Path, the mission's goals in order); and /rei/monitor (std_msgs/String, JSON)
what `rei watch`'s screen shows: the robot's and every object's FAR / CLOSE / COLLISION
state, the task, the total utility, at the end the verdict. Messages are stamped with
simulated time, and the server's clock (the ``time`` capability) follows it.

A client that subscribes late still gets the scene: the latched channels (/tf_static,
/world/markers, /rei/goals) and the latest /tf of every body are sent again to it when it
subscribes. The server listens on loopback only and never accepts messages from clients.
This module must never import the simulator; foxglove-sdk is imported when a server starts,
with an install hint when it is missing.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable, Sequence
from typing import Any

from rei.runtime.messages import Sample, StreamHeader
from rei.runtime.messages.ros import MAP, TEXT, TOPICS, MovedBodies, RosViews, stamp_ns
from rei.runtime.observation.evaluator.signal_log import SignalRow
from rei.runtime.presentation.live.frames import WatchError, WatchFrame
from rei.runtime.trace import TraceEncoder

HOST = "127.0.0.1"
LIVE_TOPICS = ("/tf", "/tf_static", "/scan", "/odom", "/cmd_vel", "/world/markers",
               "/rei/events", "/rei/signals")
"""The recording's channels this server fills (types from ``TOPICS``): a channel the
recording gains is advertised here only once this server fills it too, never empty."""
TRACE_TOPIC = "/rei/trace"
PATH_TOPIC = "/rei/path"
GOALS_TOPIC = "/rei/goals"
MONITOR_TOPIC = "/rei/monitor"
PATH = "nav_msgs/msg/Path"
PATH_STEP = 0.05
"""m: the robot's route gets a new pose when it moved this far (a path of every sample of
a long run would grow by the sample rate, for nothing a viewer can see)."""
BACKLOG = 16384
"""Messages queued per client before the oldest are dropped: a replay at full speed sends
a burst (some six messages per sample) that a client on a busy machine reads behind."""
INSTALL_HINT = ("the Foxglove server needs the 'foxglove-sdk' package: "
                "pip install 'rei-testbed[watch]' (or pip install 'foxglove-sdk>=0.30,<0.31')")


def _sdk() -> Any:
    try:
        import foxglove  # noqa: PLC0415  (optional back end, imported when used)
    except ImportError:
        raise WatchError(INSTALL_HINT) from None
    return foxglove


class FoxgloveView:
    """See the module's docstring. ``port`` 0 lets the system choose (``self.port`` tells)."""

    def __init__(self, port: int, on_subscribe: Callable[[str], None] | None = None) -> None:
        if not 0 <= port <= 65535:
            raise WatchError(f"a Foxglove port expected between 0 and 65535, found {port}")
        self.requested = port
        self.port = port
        self.on_subscribe = on_subscribe
        """Told the topic of every subscription (``rei watch --wait`` starts on the first)."""
        self._sdk = _sdk()
        self._lock = threading.Lock()
        self._views = RosViews()
        self._encoder = TraceEncoder(f"the Foxglove server's {TRACE_TOPIC}")
        self._context: Any = None
        self._server: Any = None
        self._channels: dict[str, Any] = {}
        self._latched: dict[str, bytes] = {}
        self._header: StreamHeader | None = None
        self._last: Sample | None = None
        self._moved = MovedBodies()
        self._route: list[tuple[float, float, float, float]] = []

    # ---- the server --------------------------------------------------------------------------

    def serve(self) -> int:
        """Start the server (before the stream: a client may connect and wait); its port."""
        sdk = self._sdk
        from foxglove.websocket import Capability  # noqa: PLC0415

        self._context = sdk.Context()
        view = self

        class Listener:
            def on_subscribe(self, client: Any, channel: Any) -> None:
                view._subscribed(str(channel.topic))

        try:
            self._server = sdk.start_server(
                name="REI watch", host=HOST, port=self.requested, context=self._context,
                capabilities=[Capability.Time], server_listener=Listener(),
                message_backlog_size=BACKLOG)
        except RuntimeError as exc:
            raise WatchError(f"cannot start the Foxglove server on {HOST}:{self.requested}: "
                             f"{exc}") from None
        self.port = int(self._server.port)
        # advertised before the stream starts, so a client can subscribe and be waited for
        with self._lock:
            for topic, msgtype in {**{t: TOPICS[t] for t in LIVE_TOPICS}, PATH_TOPIC: PATH,
                                   GOALS_TOPIC: PATH, MONITOR_TOPIC: TEXT}.items():
                self._channels[topic] = self._channel(topic, msgtype)
            self._channels[TRACE_TOPIC] = sdk.Channel(
                TRACE_TOPIC, schema=sdk.Schema(name="rei/TraceRecord", encoding="jsonschema",
                                               data=b'{"type":"object"}'),
                message_encoding="json", context=self._context)
        return self.port

    @property
    def url(self) -> str:
        return f"ws://{HOST}:{self.port}"

    def _channel(self, topic: str, msgtype: str) -> Any:
        sdk = self._sdk
        schema = sdk.Schema(name=msgtype, encoding="ros2msg",
                            data=self._views.store.generate_msgdef(msgtype, ros_version=2)[0]
                            .encode("utf-8"))
        return sdk.Channel(topic, schema=schema, message_encoding="cdr", context=self._context)

    # ---- the view ----------------------------------------------------------------------------

    def start(self, header: StreamHeader) -> None:
        if self._server is None:
            self.serve()
        views = self._views
        with self._lock:
            self._header = header
            self._latched = {"/tf_static": views.laser_mount(header, 0.0),
                             "/world/markers": views.markers(header, 0.0),
                             GOALS_TOPIC: self._goals(header)}
            for topic, data in self._latched.items():
                self._log(topic, 0.0, data)
            self._log_json(0.0, self._encoder.header(header))

    def show(self, frame: WatchFrame, sample: Sample | None, fired: Sequence[SignalRow]
             ) -> None:
        header = self._header
        if header is None:
            return
        views = self._views
        with self._lock:
            for row in fired:
                self._log("/rei/signals", row.time, views.text(
                    {"time": row.time, "signal": row.signal, "utility": row.utility,
                     "total_utility": row.total_utility, "objects": list(row.objects)}))
            self._log(MONITOR_TOPIC, frame.time, views.text(monitor_json(frame)))
            if sample is None:
                if frame.ended is not None and frame.end_time is not None:
                    # the trace's end line, as the recording's /rei/trace ends
                    self._log_json(frame.end_time, self._encoder.end(
                        frame.end_time, frame.ended.outcome, frame.ended.reason))
                return
            t = sample.time
            self._server.broadcast_time(stamp_ns(t))
            self._log_json(t, self._encoder.sample(sample))
            # the recording's messages of the sample (``_log`` skips a topic this server
            # has no channel for)
            for topic, message in views.sample(sample, header, self._moved.rows(sample),
                                               1.0 / header.rate):
                self._log(topic, t, message)
            for event in sample.events:
                self._log("/rei/events", event.time, views.event(event))
            if self._route_grew(sample):
                self._log(PATH_TOPIC, t, self._path(self._route, t))
            self._last = sample

    def close(self) -> None:
        """Keeps serving (a viewer may still look at the end); ``stop`` ends the server."""

    def stop(self) -> None:
        with self._lock:
            for channel in self._channels.values():
                channel.close()
            self._channels = {}
            if self._server is not None:
                self._server.stop()
                self._server = None

    # ---- helpers -----------------------------------------------------------------------------

    def _subscribed(self, topic: str) -> None:
        # Called on the server's thread: a late client gets the scene it missed.
        with self._lock:
            header, last = self._header, self._last
            if topic in self._latched:
                self._log(topic, 0.0, self._latched[topic])
            elif topic == "/tf" and header is not None and last is not None:
                self._log("/tf", last.time, self._views.transforms(
                    last, header, range(len(header.objects))))
            elif topic == PATH_TOPIC and last is not None and self._route:
                self._log(PATH_TOPIC, last.time, self._path(self._route, last.time))
        if self.on_subscribe is not None:
            self.on_subscribe(topic)

    def _log(self, topic: str, time: float, data: bytes) -> None:
        channel = self._channels.get(topic)
        if channel is not None:
            channel.log(data, log_time=stamp_ns(time))

    def _log_json(self, time: float, line: str) -> None:
        channel = self._channels.get(TRACE_TOPIC)
        if channel is not None:
            channel.log(line.encode("utf-8"), log_time=stamp_ns(time))

    def _route_grew(self, sample: Sample) -> bool:
        x, y, yaw = sample.robot_pose
        if self._route:
            _, px, py, _ = self._route[-1]
            if math.hypot(x - px, y - py) < PATH_STEP:
                return False
        self._route.append((sample.time, x, y, yaw))
        return True

    def _path(self, poses: Sequence[tuple[float, float, float, float]], time: float) -> bytes:
        t = self._views.store.types

        def stamp(at: float) -> Any:
            ns = stamp_ns(at)
            return t["std_msgs/msg/Header"](
                t["builtin_interfaces/msg/Time"](ns // 1_000_000_000, ns % 1_000_000_000), MAP)

        stamped = [t["geometry_msgs/msg/PoseStamped"](stamp(at), t["geometry_msgs/msg/Pose"](
            t["geometry_msgs/msg/Point"](x, y, 0.0),
            t["geometry_msgs/msg/Quaternion"](0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))))
            for at, x, y, yaw in poses]
        return bytes(self._views.store.serialize_cdr(t[PATH](stamp(time), stamped), PATH))

    def _goals(self, header: StreamHeader) -> bytes:
        facts = header.mission_facts
        goals = facts.goals if facts is not None else ()
        return self._path([(0.0, g.x, g.y, g.heading or 0.0) for g in goals], 0.0)


def monitor_json(frame: WatchFrame) -> dict[str, Any]:
    """What `rei watch`'s screen shows, for Foxglove's panels (/rei/monitor): the robot's,
    the laser's and every object's geometric state, the task, the total utility."""
    from rei.runtime.results import judge  # noqa: PLC0415

    return {
        "time": frame.time, "robot_state": frame.robot_state, "laser_state": frame.laser_state,
        "nav_state": frame.nav_state, "task": frame.task, "total_utility": frame.total_utility,
        "signals": frame.signals, "time_factor": frame.time_factor,
        "objects": {o.name: {"state": o.state,
                             "distance": o.distance if math.isfinite(o.distance) else None}
                    for o in frame.objects},
        "tasks": {t.name: t.status for t in frame.tasks},
        **({"outcome": frame.ended.outcome, "verdict": judge(frame.ended)}
           if frame.ended is not None else {}),
    }
