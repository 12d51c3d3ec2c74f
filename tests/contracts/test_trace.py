"""The trace file: written, read back bit-identical, refused with a clear error when foreign."""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from rei.catalogue import Box, Cylinder
from rei.runtime.messages import (
    SCHEMA_VERSION,
    GoalFacts,
    LaserScan,
    MissionEvent,
    MissionFacts,
    NavState,
    ObservedObject,
    RobotBelief,
    Sample,
    StreamHeader,
)
from rei.runtime.trace import TraceError, read_trace, read_trace_end, write

FACTS = MissionFacts((GoalFacts("start", 0.0, 0.0, None, 0.25, 0.2617993877991494, 30.0),
                      GoalFacts("elevator", 1.0, -2.5, -np.pi / 2, 0.3, 0.1, 300.0)),
                     2, 660.0, 0.26, 1.82, None)


def _header(facts: MissionFacts | None = FACTS) -> StreamHeader:
    return StreamHeader(SCHEMA_VERSION, "w", "m", 7, 10.0,
                        ObservedObject("bot", "static", "turtlebot3_waffle",
                                       Box(0.281, 0.306), 0.141),
                        (ObservedObject("wall_1", "wall", "wall", Box(1.0, 1.0), 1.2),
                         ObservedObject("walker", "human", "human", Cylinder(0.25), 1.75)),
                        1.0, (("a", 0.0, 0.0), ("b", 1.0, 0.0)), (-0.064, 0.0), facts)


def _samples() -> list[Sample]:
    rng = np.random.default_rng(0)
    out = []
    for i in range(5):
        poses = np.array([[1.0, 2.0, 0.0], rng.normal(size=3)])
        twists = np.array([[0.0, 0.0, 0.0], rng.normal(size=3)])
        scan = LaserScan(-np.pi, np.pi / 2, 0.12, 3.5, rng.uniform(0.12, 3.5, 4)) if i % 2 else None
        belief = RobotBelief((0.1 * i, 1 / 3, -0.0), (0.2, 0.1), 1.5, scan,
                             NavState.ACTIVE, "goal", (2.0 / 3 * i, -0.1 * i))
        events = {0: (MissionEvent("task_start", 0.0, "goal", 0),),
                  3: (MissionEvent("task_fail", 0.3, "goal", 0, "heading off by 37.2° "
                                   "(tolerance 15°)", "heading"),)}.get(i, ())
        contacts = {2: (1,), 3: (0, 1)}.get(i, ())
        out.append(Sample(i, i / 10, (0.1 * i, 1e-17, 3.0), (0.1, 0.0, 0.0), poses, twists,
                          belief, events, contacts))
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
        assert (a.seq, a.time, a.robot_pose, a.robot_twist, a.events, a.contacts) == \
               (b.seq, b.time, b.robot_pose, b.robot_twist, b.events, b.contacts)
        assert a.belief.cmd == b.belief.cmd
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
    with pytest.raises(TraceError, match=":1: expected a REI trace header with the field "
                                         "'laser_mount', found none"):
        read_trace(path)


def test_the_new_fields_of_schema_3_and_4_roundtrip(tmp_path: Path) -> None:
    path = tmp_path / "trace.jsonl"
    write(path, _header(), _samples(), 0.4)
    header, rows = read_trace(path)
    assert header.mission_facts == FACTS and header.version == SCHEMA_VERSION == 4
    samples = list(rows)
    assert [s.contacts for s in samples] == [(), (), (1,), (0, 1), ()]
    assert samples[4].belief.cmd == (2.0 / 3 * 4, -0.1 * 4)
    assert samples[3].events[0].cause == "heading"
    # A stream not made by a mission run has no facts; that reads back as None.
    write(path, _header(None), _samples(), 0.4)
    header, rows = read_trace(path)
    assert header.mission_facts is None and len(list(rows)) == 5


def _corrupt_sample(path: Path, line: int, change: Callable[[dict[str, Any]], None]) -> None:
    lines = path.read_text().splitlines()
    data = json.loads(lines[line - 1])
    change(data)
    lines[line - 1] = json.dumps(data)
    path.write_text("\n".join(lines) + "\n")


def _set(*keys_and_value: Any) -> Callable[[dict[str, Any]], None]:
    *keys, value = keys_and_value

    def change(data: dict[str, Any]) -> None:
        for key in keys[:-1]:
            data = data[key]
        data[keys[-1]] = value
    return change


@pytest.mark.parametrize(("change", "message"), [
    (_set("belief", "cmd", [float("nan"), 0.0]),
     r":3: belief.cmd: expected two finite numbers \[linear, angular\], found \[nan, 0.0\]"),
    (_set("belief", "cmd", [0.1]), r":3: belief.cmd: expected two finite numbers .*\[0.1\]"),
    (_set("belief", "cmd", None), r":3: belief.cmd: .* found None"),
    (_set("contacts", [2]),
     r":3: contacts: expected indices of the header's 2 objects \(0 to 1\) in increasing "
     r"order, found \[2\]"),
    (_set("contacts", [1, 0]), r":3: contacts: .* in increasing order, found \[1, 0\]"),
    (_set("contacts", [-1]), r":3: contacts: .* found \[-1\]"),
    (_set("contacts", [0.5]), r":3: contacts: .* found \[0.5\]"),
    (_set("contacts", [True]), r":3: contacts: .* found \[True\]"),
    (_set("contacts", "0"), r":3: contacts: .* found '0'"),
    (_set("events", [{"kind": "task_fail", "time": 0.1, "task": "goal", "index": 0,
                      "reason": "", "cause": "bad luck"}]),
     r":3: events\[0\].cause: expected one of 'aborted', .*'abandoned', 'cut' for kind "
     r"'task_fail', found 'bad luck'"),
    (_set("events", [{"kind": "end", "time": 0.1, "task": None, "index": None,
                      "reason": "", "cause": "timeout"}]),
     r":3: events\[0\].cause: expected one of '' for kind 'end', found 'timeout'"),
])
def test_corrupted_new_sample_fields_are_located_errors(
        tmp_path: Path, change: Callable[[dict[str, Any]], None], message: str) -> None:
    path = tmp_path / "trace.jsonl"
    write(path, _header(), _samples(), 0.4)
    _corrupt_sample(path, 3, change)  # line 3: the sample of seq 1
    _, rows = read_trace(path)
    with pytest.raises(TraceError, match=f"^{re.escape(str(path))}{message}"):
        list(rows)


def _goal_json() -> dict[str, Any]:
    return {"name": "g", "x": 0.0, "y": 0.0, "heading": None, "tolerance": 0.25,
            "heading_tolerance": 0.26, "timeout": 30.0}


@pytest.mark.parametrize(("change", "message"), [
    (_set("mission_facts", "speed_limit", 0.0),
     r"mission_facts.speed_limit: expected a finite number > 0, found 0.0"),
    (_set("mission_facts", "time_limit", float("inf")),
     r"mission_facts.time_limit: expected a finite number > 0, found inf"),
    (_set("mission_facts", "mission_max_speed", -1),
     r"mission_facts.mission_max_speed: expected a finite number > 0, found -1"),
    (_set("mission_facts", "cycles", 0),
     r"mission_facts.cycles: expected a whole number >= 1, found 0"),
    (_set("mission_facts", "cycles", 1.5), r"mission_facts.cycles: .* found 1.5"),
    (_set("mission_facts", "goals", []),
     r"mission_facts.goals: expected at least one goal, found none"),
    (_set("mission_facts", "goals", [{**_goal_json(), "x": float("nan")}]),
     r"mission_facts.goals\[0\].x: expected a finite number, found nan"),
    (_set("mission_facts", "goals", [{**_goal_json(), "heading": 4.0}]),
     r"mission_facts.goals\[0\].heading: expected a finite number >= -3.141592654 and <= "
     r"3.141592654, found 4.0"),
    (_set("mission_facts", "goals", [{**_goal_json(), "heading_tolerance": 0}]),
     r"mission_facts.goals\[0\].heading_tolerance: expected a finite number > 0 and <= "
     r"3.141592654, found 0"),
    (_set("mission_facts", "goals", [{**_goal_json(), "tolerance": "0.3"}]),
     r"mission_facts.goals\[0\].tolerance: expected a finite number > 0, found '0.3'"),
    (_set("mission_facts", "goals", [{**_goal_json(), "name": 3}]),
     r"mission_facts.goals\[0\].name: expected a string, found 3"),
    (_set("mission_facts", [1, 2]),
     r"mission_facts: expected the mission's facts \(a JSON object, or null\), found \[1, 2\]"),
])
def test_bad_mission_facts_are_located_errors(
        tmp_path: Path, change: Callable[[dict[str, Any]], None], message: str) -> None:
    path = tmp_path / "trace.jsonl"
    write(path, _header(), _samples(), 0.4)
    _corrupt_sample(path, 1, change)
    with pytest.raises(TraceError, match=f"^{re.escape(str(path))}:1: {message}"):
        read_trace(path)


def test_a_schema_2_trace_is_refused_with_a_hint(tmp_path: Path) -> None:
    path = tmp_path / "trace.jsonl"
    write(path, _header(), _samples(), 0.4)
    _corrupt_sample(path, 1, _set("version", 2))
    with pytest.raises(TraceError, match=r"sample schema 4 \(or 3\), found 1 with schema 2 "
                                         r".*record it again"):
        read_trace(path)
