"""Damaged recordings never pass (issue 13.1): every field of a trace is checked at the edge.

Real recordings of ``examples/simple_wall`` are corrupted the ways an attacker measured
(NaN footprint, zero rate, negative time, a pose row at index -1, a second end line, ...);
each is a located input error: ``rei replay`` exits 2 with ``path:line: field: expected X,
found Y`` and writes no verdicts. A mutation fuzzer then damages the recording of a failing
run at random and checks that replay never passes it and never fails any other way.
"""

from __future__ import annotations

import copy
import json
import math
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from rei.catalogue import Box, Cylinder, Polygon
from rei.runtime.commands.cli import main as rei
from rei.runtime.commands.replay import replay
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
from rei.runtime.results import judge
from rei.runtime.runs.session import run_into
from rei.runtime.trace import TraceError, TraceWriter, read_trace, read_trace_end, write
from tests.conftest import EXAMPLES

MISSION = EXAMPLES / "simple_wall" / "simple_wall.mission"


@pytest.fixture(scope="module")
def failing(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A real run that fails: teleop drives into the east wall (and misses its goal)."""
    out = tmp_path_factory.mktemp("failing")
    summary, _ = run_into(MISSION, out, controller="teleop")
    assert judge(summary) == "fail" and summary.outcome == "failed"
    return out


@pytest.fixture(scope="module")
def passing(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A real run that passes: the reference controller reaches both goals."""
    out = tmp_path_factory.mktemp("passing")
    summary, _ = run_into(MISSION, out)
    assert judge(summary) == "pass"
    return out


def _lines(run: Path) -> list[Any]:
    return [json.loads(line) for line in (run / "trace.jsonl").read_text().splitlines()]


def _save(path: Path, lines: list[Any]) -> Path:
    path.write_text("".join((x if isinstance(x, str) else json.dumps(x)) + "\n" for x in lines),
                    encoding="utf-8")
    return path


def _corrupt(run: Path, change: Callable[[list[Any]], None], path: Path) -> Path:
    lines = _lines(run)
    change(lines)
    return _save(path, lines)


def _read_all(path: Path) -> None:
    _, samples = read_trace(path)
    for _ in samples:
        pass
    read_trace_end(path)


def _replay_cli(trace: Path, out: Path, capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    capsys.readouterr()
    status = rei(["replay", str(trace), "-o", str(out)])
    captured = capsys.readouterr()
    return status, captured.err if status == 2 else captured.out


def _assert_input_error(status: int, err: str, trace: Path, message: str, out: Path) -> None:
    """Exit 2 with one located line, and no verdicts written."""
    assert status == 2
    assert err.count("\n") == 1 and "Traceback" not in err
    assert re.match(f"^rei: error: {re.escape(str(trace))}{message}", err), err
    assert not (out / "summary.json").exists()


# ---- the attacker's cases, through the real `rei replay` ----------------------------------


def test_a_nan_robot_footprint_is_an_input_error_not_a_verdict(
        failing: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    trace = _corrupt(failing, lambda x: x[0]["robot"]["footprint"].update(
        size=[math.nan, math.nan]), tmp_path / "trace.jsonl")
    status, err = _replay_cli(trace, tmp_path / "out", capsys)
    _assert_input_error(status, err, trace, r":1: robot.footprint.size: expected two finite "
                        r"numbers > 0 \[size_x, size_y\], found \[nan, nan\]$", tmp_path / "out")


def test_a_failed_end_line_followed_by_a_completed_one_is_refused(
        failing: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    lines = _lines(failing)
    assert lines[-1]["outcome"] == "failed"
    n = len(lines)
    trace = _save(tmp_path / "trace.jsonl",
                  [*lines, {"end": lines[-1]["end"], "outcome": "completed", "reason": ""}])
    status, err = _replay_cli(trace, tmp_path / "out", capsys)
    _assert_input_error(status, err, trace, f":{n + 1}: expected nothing after the end line "
                        f"\\(line {n}\\), found another line$", tmp_path / "out")
    with pytest.raises(TraceError, match=f":{n + 1}: expected nothing after the end line"):
        read_trace_end(trace)


def test_a_nan_end_time_is_refused(passing: Path, tmp_path: Path,
                                   capsys: pytest.CaptureFixture[str]) -> None:
    lines = _lines(passing)
    last = lines[-2]["time"]
    lines[-1]["end"] = math.nan
    trace = _save(tmp_path / "trace.jsonl", lines)
    status, err = _replay_cli(trace, tmp_path / "out", capsys)
    _assert_input_error(status, err, trace, f":{len(lines)}: end: expected a finite number >= "
                        f"{last:g} \\(the last sample's time\\), found nan$", tmp_path / "out")


@pytest.mark.parametrize(("change", "message"), [
    (lambda x: x[1].update(time="abc"), r":2: time: expected a finite number >= 0, found 'abc'"),
    (lambda x: x[1].update(robot_pose=[0.0, 0.0]),
     r":2: robot_pose: expected three finite numbers \[x, y, yaw\], found \[0.0, 0.0\]"),
    (lambda x: x.__setitem__(0, [1, 2]),
     r":1: expected a REI trace header \(a JSON object\), found \[1, 2\]"),
], ids=["time-abc", "two-number-pose", "list-header"])
def test_wrong_types_are_located_input_errors_not_tracebacks(
        passing: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str],
        change: Callable[[list[Any]], None], message: str) -> None:
    trace = _corrupt(passing, change, tmp_path / "trace.jsonl")
    status, err = _replay_cli(trace, tmp_path / "out", capsys)
    _assert_input_error(status, err, trace, message + "$", tmp_path / "out")


# ---- the attacker's cases, through the reader ----------------------------------------------


def _set_header(key: str, value: Any) -> Callable[[list[Any]], None]:
    return lambda x: x[0].update({key: value})


@pytest.mark.parametrize(("change", "message"), [
    (_set_header("rate", 0), r":1: rate: expected a finite number > 0, found 0$"),
    (_set_header("rate", math.nan), r":1: rate: expected a finite number > 0, found nan$"),
    (_set_header("rate", -10.0), r":1: rate: expected a finite number > 0, found -10.0$"),
    (_set_header("rate", True), r":1: rate: expected a finite number > 0, found True$"),
    (_set_header("tile_size", math.nan), r":1: tile_size: expected a finite number > 0, found "
                                         r"nan$"),
    (lambda x: x[0]["floors"][1].__setitem__(2, math.nan),
     r":1: floors\[1\]: expected \[name, x, y\] with two finite numbers, found \['middle', 1.0, "
     r"nan\]$"),
    (lambda x: x[3].update(time=-5.0),
     r":4: time: expected a finite number >= 0.1 \(the previous sample's time\), found -5.0$"),
    (lambda x: x[1].update(time=-0.5), r":2: time: expected a finite number >= 0, found -0.5$"),
    (lambda x: x[1]["events"][0].update(kind="bogus"),
     r":2: events\[0\].kind: expected one of 'begin', 'task_start', 'task_success', "
     r"'task_fail', 'end', found 'bogus'$"),
    (lambda x: x[2]["poses"].append([-1, 1.5, 0.0, 0.0]),
     r":3: poses\[0\]\[0\]: expected an index of the header's 8 objects \(0 to 7\), found -1$"),
    (lambda x: x[2]["twists"].append([8, 0.0, 0.0, 0.0]),
     r":3: twists\[0\]\[0\]: expected an index of the header's 8 objects \(0 to 7\), found 8$"),
], ids=["rate-0", "rate-nan", "rate-negative", "rate-bool", "tile-size-nan", "floor-nan",
        "time-backwards", "time-negative", "unknown-kind", "pose-index-minus-1",
        "twist-index-past-the-table"])
def test_the_attackers_corruptions_are_located_errors(
        passing: Path, tmp_path: Path, change: Callable[[list[Any]], None], message: str) -> None:
    trace = _corrupt(passing, change, tmp_path / "trace.jsonl")
    with pytest.raises(TraceError, match=f"^{re.escape(str(trace))}{message}"):
        _read_all(trace)


def test_a_pose_row_at_index_minus_one_no_longer_moves_the_last_object(
        failing: Path, tmp_path: Path) -> None:
    """Python's negative indexing used to put row -1 on the last wall, silently."""
    trace = _corrupt(failing, lambda x: x[5]["poses"].append([-1, 9.0, 9.0, 0.0]),
                     tmp_path / "trace.jsonl")
    _, samples = read_trace(trace)
    assert [s.seq for s in (next(samples) for _ in range(4))] == [0, 1, 2, 3]
    with pytest.raises(TraceError, match=r":6: poses\[0\]\[0\]: expected an index .* found -1"):
        next(samples)


# ---- every other rule ------------------------------------------------------------------------


def _event(kind: str, time: float, task: str | None = None, index: int | None = None,
           cause: str = "") -> dict[str, Any]:
    return {"kind": kind, "time": time, "task": task, "index": index, "reason": "",
            "cause": cause}


def _drop_line(i: int) -> Callable[[list[Any]], None]:
    return lambda x: x.__delitem__(i)


@pytest.mark.parametrize(("change", "message"), [
    # JSON types: a bool is not a number, a string is not a list
    (lambda x: x[1].update(seq=True),
     r":2: seq: expected 0 \(samples are numbered 0, 1, 2, ... without gaps\), found True"),
    (lambda x: x[1]["belief"].update(laser_min="0.4"),
     r":2: belief.laser_min: expected a finite number >= 0, found '0.4'"),
    (lambda x: x[1]["belief"]["scan"]["ranges"].__setitem__(7, None),
     r":2: belief.scan.ranges\[7\]: expected a finite number >= 0, found None"),
    (lambda x: x[1]["belief"]["scan"]["ranges"].__setitem__(3, -0.2),
     r":2: belief.scan.ranges\[3\]: expected a finite number >= 0, found -0.2"),
    (lambda x: x[1]["belief"]["scan"]["ranges"].__setitem__(9, 10**400),
     r":2: belief.scan.ranges\[9\]: expected a finite number >= 0, found 1000"),
    (lambda x: x[1]["belief"]["scan"]["ranges"].__setitem__(5, True),
     r":2: belief.scan.ranges\[5\]: expected a finite number >= 0, found True"),
    (lambda x: x[1]["belief"]["scan"].update(ranges=[]),
     r":2: belief.scan.ranges: expected at least one range, found none"),
    (lambda x: x[1]["belief"]["scan"].update(range_max=0.1),
     r":2: belief.scan.range_max: expected a finite number > 0.12 \(range_min\), found 0.1"),
    (lambda x: x[1]["belief"].update(nav_state="lost"),
     r":2: belief.nav_state: expected one of 'idle', .* found 'lost'"),
    (lambda x: x[1]["belief"].update(task=3), r":2: belief.task: expected a string or null, "
                                              r"found 3"),
    (lambda x: x[1].update(robot_twist=[0.0, 0.0, math.inf]),
     r":2: robot_twist: expected three finite numbers \[vx, vy, wz\], found \[0.0, 0.0, inf\]"),
    (lambda x: x[1].update(events={}), r":2: events: expected a list of mission events, "
                                       r"found \{\}"),
    # fields: none missing, none unknown
    (lambda x: x[2].pop("belief"), r":3: expected a sample line \(a JSON object\) with the "
                                   r"field 'belief', found none"),
    (lambda x: x[2]["belief"].update(mood="happy"),
     r":3: belief: expected only the fields cmd, .*, found the unknown field 'mood'"),
    (lambda x: x[0].pop("seed"), r":1: expected a REI trace header with the field 'seed'"),
    (lambda x: x[0].update(seed=-1), r":1: seed: expected a whole number >= 0, found -1"),
    # order: no gaps, no repeats, time never goes back, events in their samples
    (_drop_line(3), r":4: seq: expected 2 \(samples are numbered .*\), found 3"),
    (lambda x: x.insert(3, x[2]), r":4: seq: expected 2 .* found 1"),
    (lambda x: x[1]["events"].append(_event("begin", 0.0)),
     r":2: events\[2\].kind: expected 'begin' only as the first event of the mission, found it "
     r"after 2"),
    (lambda x: x[1]["events"][1].update(time=0.5),
     r":2: events\[1\].time: expected a finite number >= 0 and <= 0 \(after the previous event "
     r"or sample, by this sample\), found 0.5"),
    (lambda x: x[-2]["events"].append(_event("task_start", x[-2]["time"], "again", 2)),
     r": events\[1\].kind: expected no event after the mission's 'end' at t=12, found "
     r"'task_start'"),
    (lambda x: x[1]["events"][1].update(task=None),
     r":2: events\[1\].task: expected a string, found None"),
    (lambda x: x[1]["events"][0].update(index=0),
     r":2: events\[0\].index: expected null for kind 'begin', found 0"),
    (lambda x: x[1]["events"][1].update(index=-1),
     r":2: events\[1\].index: expected a whole number >= 0, found -1"),
    # the object table
    (lambda x: x[1]["poses"].pop(3),
     r":2: poses: expected a row for each of the header's 8 objects in the first sample, "
     r"found 7"),
    (lambda x: x[1]["poses"].__setitem__(1, [0, 0.0, 0.0, 0.0]),
     r":2: poses\[1\]\[0\]: expected an index of the header's 8 objects \(0 to 7\) above the "
     r"previous row's 0, found 0"),
    (lambda x: x[1]["poses"].__setitem__(1, [1, 0.0, 0.0]),
     r":2: poses\[1\]: expected a row \[index, a, b, c\], found \[1, 0.0, 0.0\]"),
    (lambda x: x[0]["objects"][2].update(role="ghost"),
     r":1: objects\[2\].role: expected one of 'wall', .*, found 'ghost'"),
    (lambda x: x[0]["robot"].update(footprint={"shape": "tile"}),
     r":1: robot.footprint.shape: expected one of 'box', 'cylinder', 'polygon' \(a robot has its "
     r"own footprint\), found 'tile'"),
    (lambda x: x[0]["objects"][0].update(footprint={"shape": "polygon",
                                                    "points": [[0, 0], [1, 1], [2, 2]]}),
     r":1: objects\[0\].footprint.points: expected at least three \[x, y\] points of finite "
     r"numbers enclosing an area"),
    (lambda x: x[0]["objects"][0].update(footprint={"shape": "cylinder", "radius": 0}),
     r":1: objects\[0\].footprint.radius: expected a finite number > 0, found 0"),
    (lambda x: x[0]["objects"][0].update(height=-1.2),
     r":1: objects\[0\].height: expected a finite number >= 0, found -1.2"),
    # the end line: one, last, after the last sample, with a known outcome
    (lambda x: x[-1].update(outcome="passed"),
     r": outcome: expected one of 'completed', 'failed', 'timeout', 'error', 'interrupted', "
     r"found 'passed'"),
    (lambda x: x[-1].update(end=8.0),
     r": end: expected a finite number >= 12 \(the last sample's time\), found 8.0"),
    (lambda x: x.insert(5, x[-1]), r":7: expected nothing after the end line \(line 6\)"),
    (lambda x: x.pop(), r":123: expected the end line .* found the end of the file"),
    (lambda x: x.append(""), r":124: expected nothing after the end line \(line 123\)"),
    (lambda x: x.insert(4, ""), r":5: expected a JSON object, found an empty line"),
    (lambda x: x.insert(2, "{not json"), r":3: expected a JSON object, found '\{not json'"),
    (lambda x: x.insert(2, "[" * 100_000), r":3: expected a JSON object, found a line JSON "
                                           r"cannot hold \(RecursionError"),
    (lambda x: x.insert(1, '{"seq": ' + "9" * 5000 + "}"),
     r":2: expected a JSON object, found a line JSON cannot hold \(ValueError"),
    (lambda x: x[1].update(time=10**400), r":2: time: expected a finite number >= 0, found "
                                          r"1000"),
], ids=lambda v: None if callable(v) else re.sub(r"\W+", "-", v)[:48])
def test_every_field_is_checked(passing: Path, tmp_path: Path,
                                change: Callable[[list[Any]], None], message: str) -> None:
    trace = _corrupt(passing, change, tmp_path / "trace.jsonl")
    with pytest.raises(TraceError, match=f"^{re.escape(str(trace))}:?[0-9]*{message}"):
        _read_all(trace)


def test_bytes_that_are_not_utf8_are_a_located_error(passing: Path, tmp_path: Path) -> None:
    trace = tmp_path / "trace.jsonl"
    lines = (passing / "trace.jsonl").read_bytes().split(b"\n")
    lines[4] = lines[4][:30] + b"\xff\xfe" + lines[4][32:]
    trace.write_bytes(b"\n".join(lines))
    with pytest.raises(TraceError, match=f"^{re.escape(str(trace))}:5: expected UTF-8 text, "
                                         f"found the bytes b'\\\\xff\\\\xfe"):
        _read_all(trace)


def test_a_killed_runs_partial_trace_needs_no_end_line(passing: Path, tmp_path: Path) -> None:
    lines = _lines(passing)[:-1]
    partial = _save(tmp_path / "trace.jsonl.partial", lines)
    _, samples = read_trace(partial)
    assert len(list(samples)) == len(lines) - 1
    assert read_trace_end(partial) is None
    finished = _save(tmp_path / "trace.jsonl", lines)
    with pytest.raises(TraceError, match=f":{len(lines) + 1}: expected the end line"):
        read_trace_end(finished)


def test_a_damage_deep_in_the_trace_is_found_when_reached_and_never_judged(
        failing: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    lines = _lines(failing)
    n = len(lines)
    lines[n - 3]["contacts"] = [99]
    trace = _save(tmp_path / "trace.jsonl", lines)
    _, samples = read_trace(trace)
    got = 0
    with pytest.raises(TraceError, match=f":{n - 2}: contacts: expected indices"):
        for _ in samples:
            got += 1
    assert got == n - 4  # the samples before the damaged line were read, lazily
    status, err = _replay_cli(trace, tmp_path / "out", capsys)
    _assert_input_error(status, err, trace, f":{n - 2}: contacts: ", tmp_path / "out")


def test_the_intact_failing_recording_replays_to_the_live_verdicts(
        failing: Path, tmp_path: Path) -> None:
    live = json.loads((failing / "summary.json").read_text(encoding="utf-8"))
    summary = replay(failing / "trace.jsonl", None, tmp_path / "out")
    assert [(v.requirement, v.status, v.decided_at) for v in summary.verdicts] == \
        [(v["requirement"], v["status"], v["decided_at"]) for v in live["verdicts"]]
    assert judge(summary) == "fail"
    assert "fail" in {v.status for v in summary.verdicts}


# ---- the writer refuses what the reader refuses --------------------------------------------

ROBOT = ObservedObject("bot", "robot", "turtlebot3_waffle", Box(0.281, 0.306), 0.141)


def _stream_header(objects: tuple[ObservedObject, ...] = (), rate: float = 10.0) -> StreamHeader:
    return StreamHeader(SCHEMA_VERSION, "w", "m", 0, rate, ROBOT, objects, 1.0, (), (0.0, 0.0))


def _sample(seq: int, time: float, pose: tuple[float, float, float] = (0.0, 0.0, 0.0),
            n: int = 0, events: tuple[MissionEvent, ...] = ()) -> Sample:
    belief = RobotBelief(pose, (0.0, 0.0), 3.5, None, NavState.IDLE, None)
    return Sample(seq, time, pose, (0.0, 0.0, 0.0), np.zeros((n, 3)), np.zeros((n, 3)), belief,
                  events)


@pytest.mark.parametrize(("header", "samples", "outcome", "message"), [
    (_stream_header(rate=0.0), [], "completed", r":1: rate: expected a finite number > 0"),
    (_stream_header(), [_sample(0, 0.0, (math.nan, 0.0, 0.0))], "completed",
     r":2: robot_pose: expected three finite numbers \[x, y, yaw\], found \[nan, 0.0, 0.0\]"),
    (_stream_header(), [_sample(0, 0.5), _sample(1, 0.4)], "completed",
     r":3: time: expected a finite number >= 0.5 \(the previous sample's time\), found 0.4"),
    (_stream_header(), [_sample(0, 0.0), _sample(2, 0.1)], "completed",
     r":3: seq: expected 1 \(samples are numbered"),
    (_stream_header(), [_sample(0, 0.0, events=(MissionEvent("end", 0.0),)),
                        _sample(1, 0.1, events=(MissionEvent("begin", 0.1),))], "completed",
     r":3: events\[0\].kind: expected no event after the mission's 'end' at t=0"),
    (_stream_header(), [_sample(0, 0.0)], "passed", r":3: outcome: expected one of"),
])
def test_the_writer_refuses_what_the_reader_would_refuse(
        tmp_path: Path, header: StreamHeader, samples: list[Sample], outcome: str,
        message: str) -> None:
    path = tmp_path / "trace.jsonl"
    partial = f"{path}.partial"
    with pytest.raises(TraceError, match=f"^cannot write the trace: {re.escape(partial)}"
                                         f"{message}"):
        write(path, header, samples, 0.5, outcome)
    assert not path.exists()  # a refused trace never appears as a finished one


def test_a_refused_sample_closes_the_partial_file(tmp_path: Path) -> None:
    writer = TraceWriter(tmp_path / "trace.jsonl")
    writer.start(_stream_header())
    writer.feed(_sample(0, 0.0))
    with pytest.raises(TraceError, match="robot_pose"):
        writer.feed(_sample(1, 0.1, (0.0, math.inf, 0.0)))
    assert writer.partial.read_text().count("\n") == 2  # the header and the good sample
    writer.finish(0.1, "completed", "")  # after a refusal there is nothing left to finish
    assert not writer.path.exists()


finite = st.floats(allow_nan=False, allow_infinity=False, width=64)
positive = st.floats(min_value=1e-6, max_value=1e6, allow_nan=False, allow_infinity=False)
FOOTPRINTS = st.one_of(
    st.builds(Box, positive, positive), st.builds(Cylinder, positive),
    st.just(Polygon(((0.0, 0.0), (1.0, 0.0), (0.0, 1.0)))))


@st.composite
def streams(draw: st.DrawFn) -> tuple[StreamHeader, list[Sample], float, str]:
    """A valid stream: objects, samples with times that never go back, mission events in order,
    scans now and then, contacts within the table."""
    objects = tuple(ObservedObject(f"o{i}", draw(st.sampled_from(["wall", "static", "human"])),
                                   "t", draw(FOOTPRINTS), draw(positive))
                    for i in range(draw(st.integers(0, 3))))
    n = len(objects)
    header = StreamHeader(SCHEMA_VERSION, draw(st.text(max_size=5)), "m",
                          draw(st.integers(0, 2**64)), draw(positive), ROBOT, objects,
                          draw(positive), (("f", draw(finite), draw(finite)),),
                          (draw(finite), draw(finite)), None)
    time, samples = 0.0, []
    kinds = iter([("begin", None, None), ("task_start", "g", 0), ("task_fail", "g", 0),
                  ("end", None, None)])
    for seq in range(draw(st.integers(0, 5))):
        time += draw(st.sampled_from([0.0, 0.1, 1e-9, 3.7]))
        vec = st.tuples(finite, finite, finite)
        events = []
        for _ in range(draw(st.integers(0, 2))):
            kind, task, index = next(kinds, (None, None, None))
            if kind is not None:
                events.append(MissionEvent(kind, time, task, index,  # type: ignore[arg-type]
                                           draw(st.text(max_size=5)),
                                           "timeout" if kind == "task_fail" else ""))
        scan = None
        if draw(st.booleans()):
            ranges = np.array(draw(st.lists(st.floats(0.0, 10.0), min_size=1, max_size=5)))
            scan = LaserScan(draw(finite), draw(positive), 0.0, 10.0, ranges)
        belief = RobotBelief(draw(vec), (draw(finite), draw(finite)), draw(st.floats(0.0, 10.0)),
                             scan, draw(st.sampled_from(list(NavState))),
                             draw(st.none() | st.text(max_size=3)), (draw(finite), draw(finite)))
        poses = np.array([draw(vec) for _ in range(n)]).reshape(n, 3)
        twists = np.array([draw(vec) for _ in range(n)]).reshape(n, 3)
        contacts = tuple(sorted(draw(st.sets(st.integers(0, n - 1), max_size=n)))) if n else ()
        samples.append(Sample(seq, time, draw(vec), draw(vec), poses, twists, belief,
                              tuple(events), contacts))
    end = time + draw(st.sampled_from([0.0, 0.5]))
    return header, samples, end, draw(st.sampled_from(["completed", "failed", "error"]))


@settings(max_examples=60, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(stream=streams())
def test_whatever_the_writer_writes_reads_back_bit_identical(
        tmp_path: Path, stream: tuple[StreamHeader, list[Sample], float, str]) -> None:
    header, samples, end, outcome = stream
    path = tmp_path / "trace.jsonl"
    write(path, header, samples, end, outcome, "why")
    back_header, rows = read_trace(path)
    assert back_header == header
    back = list(rows)
    assert len(back) == len(samples)
    for a, b in zip(samples, back, strict=True):
        assert repr((a.seq, a.time, a.robot_pose, a.robot_twist, a.events, a.contacts,
                     a.belief.odom, a.belief.cmd, a.belief.laser_min, a.belief.task)) == \
            repr((b.seq, b.time, b.robot_pose, b.robot_twist, b.events, b.contacts,
                  b.belief.odom, b.belief.cmd, b.belief.laser_min, b.belief.task))
        assert a.poses.tobytes() == b.poses.tobytes() and a.twists.tobytes() == b.twists.tobytes()
        assert (a.belief.scan is None) == (b.belief.scan is None)
        if a.belief.scan is not None and b.belief.scan is not None:
            assert a.belief.scan.ranges.tobytes() == b.belief.scan.ranges.tobytes()
    assert read_trace_end(path) == (end, outcome, "why")
    # and what the reader accepts, the writer writes back byte for byte
    write(tmp_path / "again.jsonl", back_header, back, end, outcome, "why")
    assert (tmp_path / "again.jsonl").read_bytes() == path.read_bytes()


@pytest.mark.parametrize("run", ["failing", "passing"])
def test_a_real_recording_read_and_written_again_is_the_same_bytes(
        run: str, request: pytest.FixtureRequest, tmp_path: Path) -> None:
    trace = request.getfixturevalue(run) / "trace.jsonl"
    header, samples = read_trace(trace)
    end = read_trace_end(trace)
    assert end is not None
    write(tmp_path / "trace.jsonl", header, list(samples), *end)
    assert (tmp_path / "trace.jsonl").read_bytes() == trace.read_bytes()


# ---- the mutation fuzzer ---------------------------------------------------------------------

BAD_VALUES = ["abc", "", True, False, None, [], {}, math.nan, math.inf, -math.inf, -1, -0.5,
              10**400, [1.0], {"x": 1}]
JUNK_LINES = [b"", b"junk", b"{}", b"[]", b"null", b'{"seq": 1}', b"\xff\xfe", b"{\"end\": 1}"]


def _paths(value: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    """Every place inside a JSON value (containers included, the root excluded)."""
    out = []
    items = value.items() if isinstance(value, dict) else enumerate(value) \
        if isinstance(value, list) else ()
    for key, child in items:
        out.append((*prefix, key))
        out.extend(_paths(child, (*prefix, key)))
    return out


def _parent(value: Any, path: tuple[Any, ...]) -> Any:
    for key in path[:-1]:
        value = value[key]
    return value


def _json(line: bytes) -> Any:
    """A line as JSON, or None when an earlier corruption already broke it."""
    try:
        return json.loads(line)
    except ValueError:
        return None


def _mutate(lines: list[bytes], data: st.DataObject) -> list[bytes]:
    """One corruption of the kinds the issue lists."""
    kind = data.draw(st.sampled_from(["value", "delete", "unknown_field", "second_end",
                                      "end_early", "truncate", "time_back", "bad_index",
                                      "bad_kind", "junk", "swap", "byte", "digit",
                                      "drop_event", "event_kind", "outcome", "scan_geometry"]),
                     label="kind")
    pick = st.integers(0, len(lines) - 1)
    samples = [i for i, line in enumerate(lines)
               if line.startswith(b'{"seq"') and isinstance(_json(line), dict)]
    if not lines:
        return [data.draw(st.sampled_from(JUNK_LINES))]
    if kind in ("value", "delete", "unknown_field"):
        i = data.draw(pick, label="line")
        obj = _json(lines[i])
        paths = _paths(obj)
        if kind != "value":
            paths = [p for p in paths if isinstance(_parent(obj, p), dict)]
        if not paths:
            return lines
        path = data.draw(st.sampled_from(paths), label="path")
        parent = _parent(obj, path)
        if kind == "value":
            parent[path[-1]] = copy.deepcopy(data.draw(st.sampled_from(BAD_VALUES)))
        elif kind == "delete":
            del parent[path[-1]]
        else:
            parent["junk"] = 1
        lines[i] = json.dumps(obj).encode()
    elif kind == "second_end":
        lines.append(b'{"end": 27.0, "outcome": "completed", "reason": ""}')
    elif kind == "end_early" and samples:
        end = lines.pop()
        lines.insert(data.draw(st.sampled_from(samples), label="at"), end)
    elif kind == "truncate":
        text = b"\n".join(lines)
        cut = data.draw(st.integers(0, max(0, len(text) - 1)), label="cut")
        lines = text[:cut].split(b"\n")
    elif kind in ("time_back", "bad_index", "bad_kind") and len(samples) > 1:
        i = data.draw(st.sampled_from(samples[1:]), label="sample")
        obj = _json(lines[i])
        field = {"time_back": "time", "bad_kind": "events"}.get(kind) or \
            data.draw(st.sampled_from(["poses", "twists", "contacts"]))
        if not isinstance(obj.get(field), float if kind == "time_back" else list):
            return lines  # an earlier corruption took the field away
        if kind == "time_back":
            obj["time"] -= data.draw(st.sampled_from([1e-9, 0.1, 0.2, 5.0]))
        elif kind == "bad_index":
            bad = data.draw(st.sampled_from([-1, -8, 8, 9, 1.5, True, "0"]))
            obj[field].append(bad if field == "contacts" else [bad, 0.0, 0.0, 0.0])
        else:
            obj["events"].append(_event(data.draw(st.sampled_from(["bogus", "", "Begin"])),
                                        0.0))
        lines[i] = json.dumps(obj).encode()
    elif kind in ("drop_event", "event_kind") and samples:
        # claims edited (issue 24.5): a mission event deleted, or its kind rewritten
        with_events = [i for i in samples if _json(lines[i]).get("events")]
        if not with_events:
            return lines
        i = data.draw(st.sampled_from(with_events), label="sample")
        obj = _json(lines[i])
        k = data.draw(st.integers(0, len(obj["events"]) - 1), label="event")
        if kind == "drop_event":
            del obj["events"][k]
        else:
            obj["events"][k]["kind"] = data.draw(st.sampled_from(
                ["task_success", "task_fail", "task_start"]), label="new kind")
            obj["events"][k]["cause"] = "position" \
                if obj["events"][k]["kind"] == "task_fail" else ""
        lines[i] = json.dumps(obj).encode()
    elif kind == "outcome":
        end = _json(lines[-1])
        if isinstance(end, dict) and "outcome" in end:
            end["outcome"] = data.draw(st.sampled_from(["completed", "failed", "timeout"]))
            lines[-1] = json.dumps(end).encode()
    elif kind == "scan_geometry" and samples:
        scanned = [i for i in samples if isinstance(_json(lines[i]).get("belief"), dict)
                   and isinstance(_json(lines[i])["belief"].get("scan"), dict)]
        if not scanned:
            return lines
        i = data.draw(st.sampled_from(scanned), label="sample")
        obj = _json(lines[i])
        obj["belief"]["scan"].update(data.draw(st.sampled_from(
            [{"angle_increment": 0.0}, {"ranges": [1.0, 1.0, 1.0]}, {"angle_min": 0.0},
             {"angle_increment": 0.5}])))
        lines[i] = json.dumps(obj).encode()
    elif kind == "junk":
        lines.insert(data.draw(st.integers(0, len(lines)), label="at"),
                     data.draw(st.sampled_from(JUNK_LINES)))
    elif kind == "swap":
        i, j = data.draw(pick, label="i"), data.draw(pick, label="j")
        lines[i], lines[j] = lines[j], lines[i]
    elif kind == "byte":
        i = data.draw(pick, label="line")
        at = data.draw(st.integers(0, max(0, len(lines[i]) - 1)), label="at")
        lines[i] = lines[i][:at] + bytes([data.draw(st.integers(0, 255))]) + lines[i][at + 1:]
    elif kind == "digit":
        # mostly a valid but different number: replay runs and judges, and must not pass
        i = data.draw(pick, label="line")
        digits = [k for k, c in enumerate(lines[i]) if 48 <= c <= 57]
        if digits:
            at = data.draw(st.sampled_from(digits), label="at")
            lines[i] = lines[i][:at] + str(data.draw(st.integers(0, 9))).encode() + \
                lines[i][at + 1:]
    return lines


# Shrinking a failure replays hundreds of times: the draws printed are enough to reproduce it.
@settings(max_examples=60, deadline=None, derandomize=True, phases=(Phase.generate,),
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow,
                                 HealthCheck.data_too_large])
@given(data=st.data())
def test_no_corruption_of_a_failing_recording_ever_passes(
        failing: Path, tmp_path_factory: pytest.TempPathFactory, data: st.DataObject) -> None:
    lines = (failing / "trace.jsonl").read_bytes().splitlines()
    for _ in range(data.draw(st.integers(1, 3), label="corruptions")):
        lines = _mutate(lines, data)
    work = tmp_path_factory.mktemp("fuzz")
    trace = work / "trace.jsonl"
    trace.write_bytes(b"".join(line + b"\n" for line in lines))
    try:
        summary = replay(trace, None, work / "out")
    except TraceError as exc:
        message = str(exc)
        # located (path:line: ...), phrased expected/found, never the last line of defence
        assert re.match(f"^{re.escape(str(trace))}:[0-9]+: ", message), message
        assert "expected" in message and "found" in message, message
        assert "damaged line" not in message, message
        return
    assert judge(summary) != "pass"


@settings(max_examples=200, deadline=None, derandomize=True, phases=(Phase.generate,),
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow,
                                 HealthCheck.data_too_large])
@given(data=st.data())
def test_the_reader_refuses_damage_only_with_located_errors(
        passing: Path, tmp_path_factory: pytest.TempPathFactory, data: st.DataObject) -> None:
    """The reader alone, many more corruptions: it reads or refuses with a located message,
    never with another exception or the last line of defence."""
    lines = (passing / "trace.jsonl").read_bytes().splitlines()
    for _ in range(data.draw(st.integers(1, 3), label="corruptions")):
        lines = _mutate(lines, data)
    trace = tmp_path_factory.mktemp("reader") / "trace.jsonl"
    trace.write_bytes(b"".join(line + b"\n" for line in lines))
    try:
        _read_all(trace)
    except TraceError as exc:
        assert re.match(f"^{re.escape(str(trace))}:[0-9]+: .*expected .*found", str(exc)), exc
        assert "damaged line" not in str(exc)


# ---- found by an independent attacker after the first round ---------------------------------

def test_a_repeated_field_cannot_hide_a_contact(failing: Path, tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    # JSON keeps the last of two equal keys: `"contacts": [1], "contacts": []` hid the wall.
    lines = (failing / "trace.jsonl").read_text(encoding="utf-8").splitlines()
    touched = next(i for i, line in enumerate(lines) if json.loads(line).get("contacts"))
    lines[touched] = lines[touched][:-1] + ', "contacts": []}'
    trace = tmp_path / "trace.jsonl"
    trace.write_text("\n".join(lines) + "\n", encoding="utf-8")
    status, err = _replay_cli(trace, tmp_path / "out", capsys)
    assert status == 2
    assert f"{trace}:{touched + 1}: expected each field once, found 'contacts' 2 times" in err


def test_a_lone_surrogate_is_a_located_error_not_a_traceback(
        failing: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    lines = (failing / "trace.jsonl").read_text(encoding="utf-8").splitlines()
    lines[0] = lines[0].replace('"to_the_wall"', '"to_the\\ud800wall"', 1)
    assert "\\ud800" in lines[0]
    trace = tmp_path / "trace.jsonl"
    trace.write_text("\n".join(lines) + "\n", encoding="utf-8")
    status, err = _replay_cli(trace, tmp_path / "out", capsys)
    assert status == 2 and "Traceback" not in err
    assert f"{trace}:1: expected text, found a lone surrogate escape" in err


def test_only_a_regular_file_is_read_as_a_trace(tmp_path: Path) -> None:
    import os

    fifo = tmp_path / "trace.jsonl"
    os.mkfifo(fifo)
    for path, kind in ((fifo, "a FIFO (named pipe)"), (Path("/dev/zero"), "a character device"),
                       (tmp_path, "a folder")):
        with pytest.raises(TraceError, match=re.escape(f"expected a regular file, found {kind}")):
            read_trace(path)


@pytest.mark.parametrize(("name", "message"), [
    ("x" * 200_000, "expected a fault name of at most 100 characters, found 200000"),
    ("<b>a;b</b>", r"expected a fault name \(letters, digits, '_'\), found '<b>a;b</b>'"),
])
def test_a_hand_edited_fault_name_is_an_input_error(
        passing: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str,
        message: str) -> None:
    """A 200,000-letter name made events.csv a field Python's csv reader refuses (a
    traceback after the verdicts were written); a ';' split it into two faults on reading."""
    def change(lines: list[Any]) -> None:
        lines[0]["faults"] = [{"name": name, "entry": "cmd_drop share 0.5"}]
        lines[1]["faults"] = [name]

    trace = _corrupt(passing, change, tmp_path / "trace.jsonl")
    status, err = _replay_cli(trace, tmp_path / "out", capsys)
    _assert_input_error(status, err, trace, f":1: faults\\[0\\].name: {message}", tmp_path / "out")
