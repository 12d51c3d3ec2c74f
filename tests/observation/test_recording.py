"""MCAP recordings: written by McapRecorder, read back with mcap's own reader and decoded with
rosbags (independent of REI's reader), read back exactly through /rei/trace, and refused or
cut short clearly when damaged."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mcap.reader import make_reader
from rosbags.typesys import Stores, get_typestore

from rei.runtime.messages import (
    SCHEMA_VERSION,
    LaserScan,
    MissionEvent,
    NavState,
    ObservedObject,
    RobotBelief,
    Sample,
    StreamHeader,
)
from rei.runtime.messages.ros import TOPICS
from rei.runtime.observation.evaluator.signal_log import SignalRow
from rei.runtime.observation.recordings import (
    TRACE_TOPIC,
    McapRecorder,
    RecordingError,
    read_recording,
    read_stream,
)
from rei.runtime.observation.recordings.writer import CHUNK_BYTES
from rei.runtime.trace import TraceEncoder, TraceError, read_trace, write
from tests.contracts.test_trace import _header, _samples

STORE = get_typestore(Stores.ROS2_HUMBLE)
ROOT = Path(__file__).resolve().parents[2]


def _record(path: Path, header: StreamHeader, samples: list[Sample], end: float = 0.4,
            signals: list[SignalRow] | None = None, chunk_bytes: int = CHUNK_BYTES) -> None:
    recorder = McapRecorder(path, (lambda: signals) if signals is not None else None,
                            chunk_bytes=chunk_bytes)
    recorder.start(header)
    for s in samples:
        recorder.feed(s)
    recorder.finish(end, "completed", "")


def _messages(path: Path) -> dict[str, list[tuple[int, bytes, str]]]:
    """Every message by topic, read with mcap's indexed reader: (log time, data, schema)."""
    out: dict[str, list[tuple[int, bytes, str]]] = {}
    with path.open("rb") as handle:
        reader = make_reader(handle)
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            assert schema is not None
            out.setdefault(channel.topic, []).append((message.log_time, message.data,
                                                      schema.name))
            if channel.topic != TRACE_TOPIC:
                assert channel.message_encoding == "cdr" and schema.encoding == "ros2msg"
    return out


def _yaw(q: object) -> float:
    return 2.0 * math.atan2(q.z, q.w)  # type: ignore[attr-defined]


def _long_samples(n: int, seed: int = 1) -> tuple[StreamHeader, list[Sample]]:
    """``n`` samples of a 360-beam robot walking past a wall and a moving human."""
    header = _header()
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        poses = np.array([[1.0, 2.0, 0.0], [0.01 * i, -1.0, 0.1 * i]])
        twists = np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0]])
        scan = LaserScan(-math.pi, 2 * math.pi / 360, 0.12, 3.5, rng.uniform(0.12, 3.5, 360))
        belief = RobotBelief((0.02 * i, 0.1, 0.01 * i), (0.2, 0.05), 0.5, scan,
                             NavState.ACTIVE, "goal", (0.2, -0.05))
        events = (MissionEvent("task_start", 0.0, "goal", 0),) if i == 0 else ()
        out.append(Sample(i, i / 10, (0.02 * i, 0.1, 0.01 * i), (0.2, 0.0, 0.05), poses,
                          twists, belief, events, ()))
    return header, out


# ---- read back with mcap's reader and rosbags -------------------------------------------------


def test_ros_channels_decode_with_rosbags_and_match_the_trace(tmp_path: Path) -> None:
    path = tmp_path / "recording.mcap"
    header, samples = _header(), _samples()
    signals = [SignalRow(0.15, "CLOSE", -1.0, -1.0, ("walker",))]
    _record(path, header, samples, signals=signals)
    topics = _messages(path)
    assert set(topics) == {TRACE_TOPIC, *TOPICS} - {"/rei/events"} | {"/rei/events"}
    for topic, rows in topics.items():
        if topic != TRACE_TOPIC:
            assert {schema for _, _, schema in rows} == {TOPICS[topic]}

    scans = [STORE.deserialize_cdr(d, TOPICS["/scan"]) for _, d, _ in topics["/scan"]]
    with_scan = [s for s in samples if s.belief.scan is not None]
    assert len(scans) == len(with_scan) == 2
    for msg, s in zip(scans, with_scan, strict=True):
        assert s.belief.scan is not None
        ranges = s.belief.scan.ranges.astype(np.float32)
        # REP 117: a beam without a return (REI's range_max) is +inf
        no_return = ranges >= np.float32(s.belief.scan.range_max)
        np.testing.assert_array_equal(msg.ranges, np.where(no_return, np.inf, ranges))
        assert msg.angle_min == pytest.approx(s.belief.scan.angle_min, abs=1e-6)
        assert msg.angle_increment == pytest.approx(s.belief.scan.angle_increment, abs=1e-6)
        assert msg.header.frame_id == "bot/laser"
        assert msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9 == pytest.approx(s.time)

    odom = [STORE.deserialize_cdr(d, TOPICS["/odom"]) for _, d, _ in topics["/odom"]]
    cmd = [STORE.deserialize_cdr(d, TOPICS["/cmd_vel"]) for _, d, _ in topics["/cmd_vel"]]
    tf = [STORE.deserialize_cdr(d, TOPICS["/tf"]) for _, d, _ in topics["/tf"]]
    assert len(odom) == len(cmd) == len(tf) == len(samples)
    latest: dict[str, tuple[float, float, float]] = {}
    for s, o, c, t in zip(samples, odom, cmd, tf, strict=True):
        x, y, yaw = s.belief.odom
        p = o.pose.pose
        assert (p.position.x, p.position.y) == (x, y)
        assert _yaw(p.orientation) == pytest.approx(yaw, abs=1e-12)
        assert (o.twist.twist.linear.x, o.twist.twist.angular.z) == s.belief.odom_twist
        assert (c.linear.x, c.angular.z) == s.belief.cmd
        for transform in t.transforms:
            assert transform.header.frame_id == "map"
            tr = transform.transform
            latest[transform.child_frame_id] = (tr.translation.x, tr.translation.y,
                                                _yaw(tr.rotation))
        # every body's latest ground-truth pose equals the sample's
        assert latest["bot"][:2] == s.robot_pose[:2]
        assert latest["bot"][2] == pytest.approx(math.remainder(s.robot_pose[2], math.tau))
        for i, obj in enumerate(header.objects):
            px, py, pyaw = s.poses[i]
            assert latest[obj.name][:2] == (px, py)
            assert math.remainder(latest[obj.name][2] - pyaw, math.tau) == pytest.approx(
                0.0, abs=1e-12)

    static = STORE.deserialize_cdr(topics["/tf_static"][0][1], TOPICS["/tf_static"])
    mount = static.transforms[0]
    assert (mount.header.frame_id, mount.child_frame_id) == ("bot", "bot/laser")
    assert (mount.transform.translation.x, mount.transform.translation.y) == header.laser_mount

    markers = STORE.deserialize_cdr(topics["/world/markers"][0][1], TOPICS["/world/markers"])
    framed = {m.header.frame_id for m in markers.markers if m.frame_locked}
    assert framed == {"bot", "wall_1", "walker"}
    floor = [m for m in markers.markers if m.ns == "floor"]
    assert [(p.x, p.y) for p in floor[0].points] == [(0.0, 0.0), (1.0, 0.0)]

    events = [json.loads(STORE.deserialize_cdr(d, TOPICS["/rei/events"]).data)
              for _, d, _ in topics["/rei/events"]]
    assert [(e["kind"], e["time"]) for e in events] == [("task_start", 0.0), ("task_fail", 0.3)]
    fired = [json.loads(STORE.deserialize_cdr(d, TOPICS["/rei/signals"]).data)
             for _, d, _ in topics["/rei/signals"]]
    assert fired == [{"time": 0.15, "signal": "CLOSE", "utility": -1.0,
                      "total_utility": -1.0, "objects": ["walker"]}]


def test_trace_channel_carries_the_exact_trace_lines(tmp_path: Path) -> None:
    header, samples = _header(), _samples()
    _record(tmp_path / "recording.mcap", header, samples)
    write(tmp_path / "trace.jsonl", header, samples, 0.4, "completed", "")
    lines = (tmp_path / "trace.jsonl").read_bytes().splitlines()
    carried = [STORE.deserialize_cdr(d, "std_msgs/msg/String").data.encode("utf-8")
               for _, d, _ in _messages(tmp_path / "recording.mcap")[TRACE_TOPIC]]
    assert carried == lines


def test_rosbags_own_readers_and_converter_read_every_channel(tmp_path: Path) -> None:
    """Issue 24.1: rosbags' Reader and AnyReader open REI's recording and decode every
    message of every channel (the trace too), and rosbags-convert copies all of it into a
    rosbag2 folder (sqlite3 and mcap storage), which reads back with the same messages."""
    from rosbags.highlevel import AnyReader  # noqa: PLC0415
    from rosbags.rosbag2 import Reader  # noqa: PLC0415

    header, samples = _long_samples(30)
    path = tmp_path / "recording.mcap"
    _record(path, header, samples, 3.0)
    write(tmp_path / "trace.jsonl", header, samples, 3.0, "completed", "")
    with Reader(path) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections if c.msgcount}
    assert counts[TRACE_TOPIC] == len(samples) + 2 and counts["/tf"] == len(samples)

    def decoded(source: Path) -> dict[str, list[Any]]:
        out: dict[str, list[Any]] = {}
        with AnyReader([source]) as reader:
            for connection, _, raw in reader.messages():
                out.setdefault(connection.topic, []).append(
                    reader.deserialize(raw, connection.msgtype))
        return out

    mine = decoded(path)
    assert {t: len(m) for t, m in mine.items()} == counts
    lines = (tmp_path / "trace.jsonl").read_text(encoding="utf-8").splitlines()
    assert [m.data for m in mine[TRACE_TOPIC]] == lines
    for storage in ("sqlite3", "mcap"):
        target = tmp_path / f"converted-{storage}"
        done = subprocess.run([str(Path(sys.executable).parent / "rosbags-convert"), "--src",
                               str(path), "--dst", str(target), "--dst-storage", storage],
                              capture_output=True, text=True, check=False)
        assert done.returncode == 0 and "ERROR" not in done.stdout + done.stderr, done
        again = decoded(target)
        assert {t: len(m) for t, m in again.items()} == counts
        assert [m.data for m in again[TRACE_TOPIC]] == lines


def test_a_trace_message_that_is_not_a_cdr_string_is_a_located_error(tmp_path: Path) -> None:
    from mcap.writer import Writer  # noqa: PLC0415

    path = tmp_path / "forged.mcap"
    with path.open("wb") as handle:
        writer = Writer(handle)
        writer.start()
        schema = writer.register_schema("std_msgs/msg/String", "ros2msg", b"string data")
        channel = writer.register_channel(TRACE_TOPIC, "cdr", schema)
        writer.add_message(channel, 0, b"\x00\x01\x00\x00\xff\xff\x00\x00{", 0)
        writer.finish()
    with pytest.raises(RecordingError, match=r"forged\.mcap: /rei/trace message 1: expected "
                                             r"a CDR std_msgs/msg/String"):
        read_recording(path)


def test_read_recording_equals_read_trace(tmp_path: Path) -> None:
    header, samples = _header(), _samples()
    _record(tmp_path / "recording.mcap", header, samples)
    write(tmp_path / "trace.jsonl", header, samples, 0.4, "completed", "")
    h1, from_trace = read_trace(tmp_path / "trace.jsonl")
    h2, from_mcap = read_recording(tmp_path / "recording.mcap")
    assert h1 == h2 == header
    a, b = list(from_trace), list(from_mcap)
    assert len(a) == len(b) == len(samples)
    # bit-identical: the two encode to the same trace lines
    ea, eb = TraceEncoder("a"), TraceEncoder("b")
    assert ea.header(h1) == eb.header(h2)
    for x, y in zip(a, b, strict=True):
        assert ea.sample(x) == eb.sample(y)
    assert from_mcap.end == (0.4, "completed", "") and from_mcap.cut_short == ""
    _, stream, end = read_stream(tmp_path / "recording.mcap", audit=False)
    assert len(list(stream)) == len(samples) and end() == (0.4, "completed", "")
    # This made-up stream's task is not its mission's goal: judged, it is refused (located).
    _, stream, end = read_stream(tmp_path / "recording.mcap")
    with pytest.raises(TraceError, match=r"recording.mcap: /rei/trace message 2: events\[0\]: "
                                         r"expected the task_start of task 'start'"):
        list(stream)


def test_same_stream_gives_identical_bytes(tmp_path: Path) -> None:
    header, samples = _long_samples(60)
    _record(tmp_path / "a.mcap", header, samples, 6.0, chunk_bytes=20_000)
    _record(tmp_path / "b.mcap", header, samples, 6.0, chunk_bytes=20_000)
    assert (tmp_path / "a.mcap").read_bytes() == (tmp_path / "b.mcap").read_bytes()


# ---- cut short by a crash ---------------------------------------------------------------------


def test_truncated_recording_gives_its_complete_prefix(tmp_path: Path) -> None:
    header, samples = _long_samples(200)
    full = tmp_path / "recording.mcap"
    _record(full, header, samples, 20.0, chunk_bytes=30_000)
    data = full.read_bytes()
    _, complete = read_recording(full)
    assert len(list(complete)) == 200
    counts = []
    cut = tmp_path / "cut.mcap"
    for offset in sorted({len(data) // 2, len(data) // 3, len(data) * 3 // 4, len(data) - 1,
                          len(data) - 9, len(data) - 200, *range(4000, len(data), 7919)}):
        cut.write_bytes(data[:offset])
        try:
            h, stream = read_recording(cut)
        except RecordingError as exc:  # before the first complete chunk: said clearly
            assert str(cut) in str(exc) and "cut short" in str(exc)
            counts.append(0)
            continue
        assert h == header
        got = list(stream)
        # a prefix of the samples, exactly
        assert [s.seq for s in got] == list(range(len(got)))
        for s, original in zip(got, samples, strict=False):
            assert s.robot_pose == original.robot_pose
        if stream.end is None:
            assert "cut short" in stream.cut_short and str(cut) in stream.cut_short
            assert f"after {len(got)} sample(s)" in stream.cut_short
        else:  # cut inside the index or summary: every record was there
            assert len(got) == 200
        counts.append(len(got))
    assert counts == sorted(counts)  # a longer prefix of the file never gives fewer samples
    assert 0 < counts[len(counts) // 2] < 200


def test_recorder_killed_mid_run_leaves_a_readable_file(tmp_path: Path) -> None:
    path = tmp_path / "recording.mcap"
    # a process that records 120 samples and dies without finishing (as a crash does)
    script = ("import os, sys\n"
              "from tests.observation.test_recording import _long_samples\n"
              "from rei.runtime.observation.recordings import McapRecorder\n"
              "header, samples = _long_samples(120)\n"
              "recorder = McapRecorder(sys.argv[1], chunk_bytes=30_000)\n"
              "recorder.start(header)\n"
              "for s in samples:\n"
              "    recorder.feed(s)\n"
              "os._exit(9)\n")
    done = subprocess.run([sys.executable, "-c", script, str(path)], cwd=ROOT, check=False)
    assert done.returncode == 9
    _, stream = read_recording(path)
    got = list(stream)
    assert 0 < len(got) < 120 and stream.end is None and "cut short" in stream.cut_short


# ---- hostile input ----------------------------------------------------------------------------


def test_not_an_mcap_file_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "recording.mcap"
    path.write_text('{"format": "rei-trace"}\n', encoding="utf-8")
    with pytest.raises(RecordingError, match=r"recording\.mcap: expected an MCAP recording"):
        read_recording(path)
    path.write_bytes(b"")
    with pytest.raises(RecordingError, match="found an empty file"):
        read_recording(path)
    with pytest.raises(RecordingError, match="expected an MCAP recording"):
        read_stream(path)


def test_mcap_without_trace_is_refused(tmp_path: Path) -> None:
    from mcap.writer import Writer  # noqa: PLC0415

    path = tmp_path / "other.mcap"
    with path.open("wb") as handle:
        writer = Writer(handle)
        writer.start()
        schema = writer.register_schema("std_msgs/msg/String", "ros2msg", b"string data")
        channel = writer.register_channel("/chatter", "cdr", schema)
        writer.add_message(channel, 0, b"\x00\x01\x00\x00\x01\x00\x00\x00\x00", 0)
        writer.finish()
    with pytest.raises(RecordingError, match=r"other\.mcap: expected a /rei/trace channel.*"
                                             r"found the topics: /chatter"):
        read_recording(path)


def test_damaged_chunk_is_refused_naming_the_file(tmp_path: Path) -> None:
    header, samples = _long_samples(100)
    path = tmp_path / "recording.mcap"
    _record(path, header, samples, 10.0, chunk_bytes=30_000)
    data = bytearray(path.read_bytes())
    middle = len(data) // 2
    data[middle:middle + 16] = bytes(16)
    path.write_bytes(bytes(data))
    with pytest.raises(RecordingError, match=r"recording\.mcap: damaged MCAP recording"):
        h, stream = read_recording(path)
        list(stream)


def test_a_bad_trace_record_is_refused_by_the_trace_rules(tmp_path: Path) -> None:
    from mcap.writer import Writer  # noqa: PLC0415

    header, samples = _header(), _samples()
    write(tmp_path / "trace.jsonl", header, samples, 0.4, "completed", "")
    lines = (tmp_path / "trace.jsonl").read_bytes().splitlines()
    lines[2] = lines[2].replace(b'"seq":1', b'"seq":5')
    path = tmp_path / "forged.mcap"
    with path.open("wb") as handle:
        writer = Writer(handle)
        writer.start()
        channel = writer.register_channel(TRACE_TOPIC, "json", 0)
        for i, line in enumerate(lines):
            writer.add_message(channel, i, line, i)
        writer.finish()
    _, stream = read_recording(path)
    with pytest.raises(TraceError, match=r"forged\.mcap: /rei/trace message 3: seq: "
                                             r"expected 1"):
        list(stream)


def test_recorder_refuses_what_the_reader_would(tmp_path: Path) -> None:
    header, samples = _header(), _samples()
    recorder = McapRecorder(tmp_path / "recording.mcap")
    recorder.start(header)
    recorder.feed(samples[0])
    bad = Sample(1, math.nan, samples[1].robot_pose, samples[1].robot_twist,
                 samples[1].poses, samples[1].twists, samples[1].belief)
    with pytest.raises(RecordingError, match="cannot write the recording: .*time: expected a "
                                             "finite number"):
        recorder.feed(bad)


def test_a_room_without_objects_and_a_flat_robot_records(tmp_path: Path) -> None:
    header = StreamHeader(SCHEMA_VERSION, "w", "m", 0, 10.0,
                          ObservedObject("r", "robot", "custom", _header().robot.footprint, 0.0),
                          (), 1.0)
    belief = _samples()[0].belief
    sample = Sample(0, 0.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), np.zeros((0, 3)),
                    np.zeros((0, 3)), belief)
    path = tmp_path / "recording.mcap"
    _record(path, header, [sample], 0.0)
    h, stream = read_recording(path)
    assert h == header and [s.seq for s in stream] == [0]
    markers = STORE.deserialize_cdr(_messages(path)["/world/markers"][0][1],
                                    TOPICS["/world/markers"])
    assert [m.header.frame_id for m in markers.markers] == ["r"]
    assert markers.markers[0].scale.z > 0  # a body of no height still shows
