"""`McapRecorder`: the sample stream as an MCAP recording with ROS 2 types.

One channel per topic (see ``rei.runtime.messages.ros.TOPICS``) with its ``ros2msg`` schema
and CDR messages, plus ``/rei/trace``: the exact JSON-lines trace (header record first, one
record per sample, then the end record; each line a ``std_msgs/msg/String``, so every ROS 2
bag reader opens and copies the whole file: rosbags' ``Reader``/``AnyReader`` and
``rosbags-convert`` among them), encoded by the trace's
own ``TraceEncoder`` and so checked by the same rules. Messages are stamped with the
simulated time (nanoseconds from the start of the run); nothing depends on the wall clock,
so the same run gives the same bytes.

The file is written in place, chunk by chunk: a chunk is closed, compressed (zstd) and
flushed to the file once it holds ``CHUNK_BYTES`` of messages, so a run that crashes leaves
a recording readable up to its last complete chunk (at most a few simulated seconds are
lost); ``finish`` writes the rest, the index and the summary. This module must never
import pybullet.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import IO

from mcap.writer import CompressionType, Writer

from rei.generators.output import open_output
from rei.runtime.messages import NavState, Sample, StreamHeader
from rei.runtime.messages.ros import (
    LATCHED,
    NAV2_STATUS_TOPIC,
    TEXT,
    TOPICS,
    MovedBodies,
    RosViews,
    stamp_ns,
    trace_cdr,
)
from rei.runtime.observation.evaluator.signal_log import SignalRow
from rei.runtime.observation.recordings.errors import RecordingError
from rei.runtime.trace import TraceEncoder, TraceError, TraceWriter

RECORDING = "recording.mcap"
"""The recording's name in a run's output folder."""

TRACE_TOPIC = "/rei/trace"
PROFILE = "ros2"

CHUNK_BYTES = 64 * 1024
"""Uncompressed message bytes per chunk: about what a crash can lose (some 3 simulated
seconds of a 10 Hz run with a 360-beam laser at 5 Hz in a small room; less in a big one)."""

_LATCHED_QOS = (
    "- history: 3\n  depth: 0\n  reliability: 1\n  durability: 1\n"
    "  deadline:\n    sec: 2147483647\n    nsec: 4294967295\n"
    "  lifespan:\n    sec: 2147483647\n    nsec: 4294967295\n"
    "  liveliness: 1\n"
    "  liveliness_lease_duration:\n    sec: 2147483647\n    nsec: 4294967295\n"
    "  avoid_ros_namespace_conventions: false\n")
"""rosbag2's offered_qos_profiles of a transient-local (latched) publisher."""


class McapRecorder:
    """A ``SampleSink`` writing ``path`` (an MCAP recording); see the module's docstring.

    ``signals``, when given, returns the signals fired so far (the monitor's signal log):
    the new ones are recorded on /rei/signals after each sample and at the end. Put the
    recorder after the monitor among the sinks, so a sample's signals are in by then.
    ``trace``, when given, is the run's ``TraceWriter``, fed before the recorder: its lines
    (encoded and checked once) are carried on /rei/trace as written, byte for byte.
    Raises ``RecordingError`` for a record the trace's reader would refuse, or a file that
    cannot be written.
    """

    def __init__(self, path: str | Path,
                 signals: Callable[[], Sequence[SignalRow]] | None = None,
                 chunk_bytes: int = CHUNK_BYTES, trace: TraceWriter | None = None) -> None:
        self.path = Path(path)
        self.signals = signals
        self.trace = trace
        self.chunk_bytes = chunk_bytes
        self._file: IO[bytes] | None = None
        self._writer: Writer | None = None
        self._encoder = TraceEncoder(f"{self.path}: {TRACE_TOPIC} message")
        self._views = RosViews()
        self._channels: dict[str, int] = {}
        self._sequence: dict[int, int] = {}
        self._header: StreamHeader | None = None
        self._pending = 0
        self._signals_seen = 0
        self._scan_time = 0.0
        self._moved = MovedBodies()
        self._task: tuple[int, float] | None = None
        """(index, start time) of the latest task started."""
        self._status: tuple[int, NavState] | None = None

    # ---- the sink ---------------------------------------------------------------------------

    def _encode(self, encode: Callable[..., str], *record: object) -> str:
        try:
            return encode(*record)
        except TraceError as exc:
            self._abandon()
            raise RecordingError(f"cannot write the recording: {exc}") from None

    def _written(self, start: str, what: str) -> str:
        """The trace writer's last line, which must be the record being recorded."""
        assert self.trace is not None
        line = self.trace.line
        if not line.startswith(start):
            self._abandon()
            raise RecordingError(f"cannot write the recording '{self.path}': expected the trace "
                                 f"writer to have written {what} (it must be fed before the "
                                 f"recorder), found {line[:40]!r}")
        return line

    def start(self, header: StreamHeader) -> None:
        record = self._written('{"format":', "the header") if self.trace is not None \
            else self._encode(self._encoder.header, header)
        self._header = header
        self._scan_time = 1.0 / header.rate
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._file = open_output(self.path, binary=True)  # never written through a link
        except OSError as exc:
            raise RecordingError(f"cannot write the recording '{self.path}': "
                                 f"{exc.strerror or exc}") from None
        # Chunks are closed here (``_add``), never by the library's own size rule.
        writer = Writer(self._file, chunk_size=2**62, compression=CompressionType.ZSTD)
        writer.start(profile=PROFILE)
        self._writer = writer
        # The trace's lines travel as std_msgs/msg/String (CDR), like /rei/events: every ROS 2
        # tool reads the channel (rosbags knows no 'jsonschema' schema encoding and refused
        # the whole file over a JSON channel; rosbags-convert cannot copy a schemaless one).
        schemas: dict[str, int] = {}
        schemas[TEXT] = writer.register_schema(TEXT, "ros2msg", self._views.schema(TEXT))
        self._channels[TRACE_TOPIC] = writer.register_channel(TRACE_TOPIC, "cdr", schemas[TEXT])
        for topic, msgtype in TOPICS.items():
            if msgtype not in schemas:
                schemas[msgtype] = writer.register_schema(msgtype, "ros2msg",
                                                          self._views.schema(msgtype))
            metadata = {"offered_qos_profiles": _LATCHED_QOS} if topic in LATCHED else {}
            self._channels[topic] = writer.register_channel(topic, "cdr", schemas[msgtype],
                                                            metadata)
        self._sequence = dict.fromkeys(self._channels.values(), 0)
        self._add(TRACE_TOPIC, 0.0, trace_cdr(record))
        self._add("/tf_static", 0.0, self._views.laser_mount(header, 0.0))
        self._add("/world/markers", 0.0, self._views.markers(header, 0.0))

    def feed(self, sample: Sample) -> None:
        header = self._header
        assert header is not None and self._writer is not None, "start() first"
        record = self._written(f'{{"seq":{sample.seq},', f"sample {sample.seq}") \
            if self.trace is not None else self._encode(self._encoder.sample, sample)
        t = sample.time
        self._add(TRACE_TOPIC, t, trace_cdr(record))
        views = self._views
        for topic, message in views.sample(sample, header, self._moved.rows(sample),
                                           self._scan_time):
            self._add(topic, t, message)
        for event in sample.events:
            if event.kind == "task_start" and event.index is not None:
                self._task = (event.index, event.time)
        if "nav_state" in header.data:
            self._goal_status(sample)
        for event in sample.events:
            self._add("/rei/events", event.time, views.event(event))
        self._record_signals()

    def finish(self, end_time: float, outcome: str, reason: str) -> None:
        if self._writer is None or self._file is None:
            return
        record = self._written('{"end":', "the end record") if self.trace is not None \
            else self._encode(self._encoder.end, end_time, outcome, reason)
        self._record_signals()
        self._add(TRACE_TOPIC, end_time, trace_cdr(record))
        try:
            self._writer.finish()  # type: ignore[no-untyped-call]
            self._file.flush()
            os.fsync(self._file.fileno())
        except OSError as exc:
            raise RecordingError(f"cannot write the recording '{self.path}': "
                                 f"{exc.strerror or exc}") from None
        finally:
            self._file.close()
            self._file = None
            self._writer = None

    # ---- helpers ----------------------------------------------------------------------------

    def _goal_status(self, sample: Sample) -> None:
        """Nav2's action status as a Nav2 stack publishes it, on every change: the running
        task's goal accepted, executing, and ended as the robot claimed (SUCCEEDED, also for
        a claim the ground truth refused, ABORTED, CANCELED). A task ended by its timeout or
        the mission's end gets no status: nothing the robot said ended it."""
        claims = {"position": NavState.SUCCEEDED, "heading": NavState.SUCCEEDED,
                  "aborted": NavState.ABORTED, "preempted": NavState.PREEMPTED}
        for event in sample.events:
            if event.index is None:
                continue
            if event.kind == "task_start":
                self._task = (event.index, event.time)
                self._publish_status(event.index, NavState.PENDING, event.time)
            elif event.kind == "task_success":
                self._publish_status(event.index, NavState.SUCCEEDED, event.time)
            elif event.kind == "task_fail" and event.cause in claims:
                self._publish_status(event.index, claims[event.cause], event.time)
        state = sample.belief.nav_state
        if self._task is not None and sample.belief.task is not None and \
                state in (NavState.PENDING, NavState.ACTIVE):
            self._publish_status(self._task[0], state, sample.time)

    def _publish_status(self, index: int, state: NavState, time: float) -> None:
        if self._task is None or (index, state) == self._status:
            return
        self._status = (index, state)
        self._add(NAV2_STATUS_TOPIC, time,
                  self._views.goal_status(index, self._task[1], state))

    def _record_signals(self) -> None:
        if self.signals is None:
            return
        rows = self.signals()
        for row in rows[self._signals_seen:]:
            self._add("/rei/signals", row.time, self._views.text(
                {"time": row.time, "signal": row.signal, "utility": row.utility,
                 "total_utility": row.total_utility, "objects": list(row.objects)}))
        self._signals_seen = len(rows)

    def _add(self, topic: str, time: float, data: bytes) -> None:
        assert self._writer is not None
        channel = self._channels[topic]
        ns = stamp_ns(time)
        sequence = self._sequence[channel]
        self._sequence[channel] = sequence + 1
        try:
            self._writer.add_message(channel, ns, data, ns, sequence)
            self._pending += len(data)
            if self._pending >= self.chunk_bytes:
                # the chunk is closed and on disk: a crash keeps it
                self._writer.flush()  # type: ignore[no-untyped-call]
                self._pending = 0
        except OSError as exc:
            self._abandon()
            raise RecordingError(f"cannot write the recording '{self.path}': "
                                 f"{exc.strerror or exc}") from None

    def _abandon(self) -> None:
        """Stop writing (after an error): what is on disk stays readable as a cut recording."""
        if self._file is not None:
            self._file.close()
        self._file = None
        self._writer = None
