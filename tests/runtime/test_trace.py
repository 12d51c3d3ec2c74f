"""The trace file: written, read back bit-identical, refused with a clear error when foreign."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from rei.catalogue import Box, Cylinder
from rei.runtime.collector import TraceError, read_trace, write
from rei.runtime.collector.trace import read_trace_end
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


def _header() -> StreamHeader:
    return StreamHeader(SCHEMA_VERSION, "w", "m", 7, 10.0,
                        ObservedObject("bot", "static", "turtlebot3_waffle",
                                       Box(0.281, 0.306), 0.141),
                        (ObservedObject("wall_1", "wall", "wall", Box(1.0, 1.0), 1.2),
                         ObservedObject("walker", "human", "human", Cylinder(0.25), 1.75)),
                        1.0, (("a", 0.0, 0.0), ("b", 1.0, 0.0)), (-0.064, 0.0))


def _samples() -> list[Sample]:
    rng = np.random.default_rng(0)
    out = []
    for i in range(5):
        poses = np.array([[1.0, 2.0, 0.0], rng.normal(size=3)])
        twists = np.array([[0.0, 0.0, 0.0], rng.normal(size=3)])
        scan = LaserScan(-np.pi, np.pi / 2, 0.12, 3.5, rng.uniform(0.12, 3.5, 4)) if i % 2 else None
        belief = RobotBelief((0.1 * i, 1 / 3, -0.0), (0.2, 0.1), 1.5, scan,
                             NavState.ACTIVE, "goal")
        events = (MissionEvent("task_start", i / 10, "goal", 0),) if i == 0 else ()
        out.append(Sample(i, i / 10, (0.1 * i, 1e-17, 3.0), (0.1, 0.0, 0.0), poses, twists,
                          belief, events))
    return out


def test_write_read_roundtrip_is_exact(tmp_path: Path) -> None:
    path = tmp_path / "trace.jsonl"
    samples = _samples()
    write(path, _header(), samples, 0.4, "completed", "")
    header, read = read_trace(path)
    assert header == _header()
    back = list(read)
    assert len(back) == len(samples)
    for a, b in zip(samples, back, strict=False):
        assert (a.seq, a.time, a.robot_pose, a.robot_twist, a.events) == \
               (b.seq, b.time, b.robot_pose, b.robot_twist, b.events)
        assert np.array_equal(a.poses, b.poses) and np.array_equal(a.twists, b.twists)
        assert a.belief.odom == b.belief.odom and a.belief.nav_state == b.belief.nav_state
        if a.belief.scan is None:
            assert b.belief.scan is None
        else:
            assert b.belief.scan is not None
            assert np.array_equal(a.belief.scan.ranges, b.belief.scan.ranges)
    assert read_trace_end(path) == (0.4, "completed", "")
    # Written twice, the bytes are the same.
    write(tmp_path / "again.jsonl", _header(), samples, 0.4)
    assert (tmp_path / "again.jsonl").read_bytes() == path.read_bytes()


def test_other_versions_and_files_are_refused(tmp_path: Path) -> None:
    path = tmp_path / "trace.jsonl"
    write(path, _header(), _samples(), 0.4)
    lines = path.read_text().splitlines()
    head = json.loads(lines[0])
    head["trace_version"] = 99
    path.write_text("\n".join([json.dumps(head), *lines[1:]]) + "\n")
    with pytest.raises(TraceError, match="expected trace version 1"):
        read_trace(path)
    other = tmp_path / "other.jsonl"
    other.write_text('{"format": "something"}\n')
    with pytest.raises(TraceError, match="expected a REI trace"):
        read_trace(other)
    with pytest.raises(TraceError, match="cannot read"):
        read_trace(tmp_path / "missing.jsonl")


def test_the_laser_mount_travels_in_the_header_and_a_bad_one_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "trace.jsonl"
    write(path, _header(), _samples(), 0.4)
    lines = path.read_text().splitlines()
    head = json.loads(lines[0])
    assert head["laser_mount"] == [-0.064, 0.0]
    header, samples = read_trace(path)
    assert header.laser_mount == (-0.064, 0.0) and len(list(samples)) == 5
    for bad, found in (([0.1], r"\[0.1\]"), (None, "None"), (["x", 0.0], r"\['x', 0.0\]")):
        head["laser_mount"] = bad
        path.write_text("\n".join([json.dumps(head), *lines[1:]]) + "\n")
        with pytest.raises(TraceError, match=f"laser_mount: expected two finite numbers .*"
                                             f"found {found}"):
            read_trace(path)
    del head["laser_mount"]
    path.write_text("\n".join([json.dumps(head), *lines[1:]]) + "\n")
    with pytest.raises(TraceError, match="damaged trace header"):
        read_trace(path)
