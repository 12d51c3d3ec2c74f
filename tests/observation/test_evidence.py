"""Evidence over claims (issue 24.5): a recording's mission events, end line and scans are
checked against its own ground truth before it is judged.

The run: simple_wall with the second goal's timeout cut to 4 s, so the reference robot is
still ~1 m short of it when the task times out (FAIL, exit 1). The issue's two forged traces
(its task_fail deleted; rewritten as task_success with a completed end line) replayed as
PASS, exit 0; here they are located input errors, in trace.jsonl and in recording.mcap
alike. A hypothesis fuzzer then edits the mission events and the end line at random: no
edit ever turns the FAIL into a PASS.
"""

from __future__ import annotations

import json
import re
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st
from mcap.reader import make_reader
from mcap.writer import Writer
from rosbags.typesys import Stores, get_typestore

from rei.runtime.commands.cli import main as rei
from rei.runtime.commands.replay import replay
from rei.runtime.observation.recordings import TRACE_TOPIC
from rei.runtime.results import judge
from rei.runtime.runs.session import run_into
from rei.runtime.trace import TraceError
from tests.conftest import EXAMPLES

STORE = get_typestore(Stores.ROS2_HUMBLE)
STRING = "std_msgs/msg/String"
TIMEOUT_MISSION = """mission to_the_wall in "simple_wall.room" {
    goal start_place at start tolerance 0.25 timeout 30
    goal at_the_wall at front tolerance 0.25 timeout 4
}
"""


@pytest.fixture(scope="module")
def timed_out(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A real run whose second task times out ~1 m from its goal (FAIL), recorded."""
    root = tmp_path_factory.mktemp("timed_out")
    shutil.copy(EXAMPLES / "simple_wall" / "simple_wall.room", root)
    (root / "timeout.mission").write_text(TIMEOUT_MISSION, encoding="utf-8")
    summary, _ = run_into(root / "timeout.mission", root / "run", recording=True)
    assert judge(summary) == "fail" and summary.outcome == "failed"
    return root / "run"


Lines = list[dict[str, Any]]


def _lines(run: Path) -> Lines:
    return [json.loads(line) for line in (run / "trace.jsonl").read_text().splitlines()]


def _save(lines: Lines, path: Path) -> Path:
    path.write_text("".join(json.dumps(x) + "\n" for x in lines), encoding="utf-8")
    return path


def _events(lines: Lines) -> list[tuple[int, int]]:
    """(line, event) positions of every mission event."""
    return [(i, k) for i, x in enumerate(lines) for k in range(len(x.get("events", ())))]


def _delete_fail(lines: Lines) -> None:
    for x in lines:
        x["events"] = [e for e in x.get("events", ()) if e["kind"] != "task_fail"] \
            if "events" in x else x.get("events")
    for x in lines:
        if x.get("events") is None:
            x.pop("events", None)


def _fail_to_success(lines: Lines) -> None:
    for x in lines:
        for e in x.get("events", ()):
            if e["kind"] == "task_fail":
                e.update(kind="task_success", reason="", cause="")
    lines[-1].update(outcome="completed", reason="all 2 tasks succeeded")


def _fail_to_success_fast(lines: Lines) -> None:
    """The success claimed a sample period early, the sample's velocity inflated to excuse
    the distance: the recorded velocity is as editable as the claim."""
    _fail_to_success(lines)
    for i, x in enumerate(lines):
        for e in x.get("events", ()):
            if e["kind"] == "task_success" and e["task"] == "at_the_wall":
                e["time"] = lines[i - 1]["time"]
                x["robot_twist"] = [100.0, 0.0, 0.0]


def _outcome_completed(lines: Lines) -> None:
    lines[-1].update(outcome="completed", reason="all 2 tasks succeeded")


def _scan(change: Callable[[dict[str, Any]], None]) -> Callable[[Lines], None]:
    def edit(lines: Lines) -> None:
        for x in lines[1:-1]:
            scan = x["belief"].get("scan")
            if scan:
                change(scan)
                return
    return edit


FORGERIES: dict[str, tuple[Callable[[Lines], None], str]] = {
    # the mission's settle period runs on after the timeout: the task overdue without its
    # task_fail is caught at that sample, before the end line
    "task_fail deleted": (_delete_fail, r"events: expected the task_fail of task 'at_the_wall' "
                                        r"\(#1; started at t=[0-9.]+ s, timeout 4 s\) by "
                                        r"t=[0-9.]+ s, found none by t=[0-9.]+ s$"),
    "task_fail rewritten as task_success, end completed": (
        _fail_to_success, r"events\[0\]\.kind: expected task_fail \(the recorded ground-truth "
                          r"pose at t=4\.2 s is 0\.9\d\d m from goal 'at_the_wall', tolerance "
                          r"0\.25 m\), found task_success"),
    "success claimed with an inflated velocity": (
        _fail_to_success_fast, r"events\[0\]\.kind: expected task_fail \(the recorded "
                               r"ground-truth pose at t=4\.2 s is 0\.9\d\d m from goal"),
    "end outcome failed -> completed": (
        _outcome_completed, r"outcome: expected 'failed' \(the events show 1 of 2 tasks "
                            r"failed\), found 'completed'"),
    "angle_increment 0": (_scan(lambda s: s.update(angle_increment=0.0)),
                          # the trace's own field rules may refuse it first
                          r"belief\.scan(: expected the geometry of one laser: an "
                          r"angle_increment > 0|\.angle_increment: expected a finite number > "
                          r"0), found 0\.0"),
    "3 ranges": (_scan(lambda s: s.update(ranges=s["ranges"][:3])),
                 r"belief\.scan: expected the geometry of one laser: 360 ranges .*found 3"),
}


@pytest.mark.parametrize("forgery", list(FORGERIES))
def test_a_forged_trace_is_a_located_error_not_a_pass(
        timed_out: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str],
        forgery: str) -> None:
    edit, message = FORGERIES[forgery]
    lines = _lines(timed_out)
    edit(lines)
    trace = _save(lines, tmp_path / "trace.jsonl")
    capsys.readouterr()
    status = rei(["replay", str(trace), "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert status == 2, err
    assert re.match(rf"^rei: error: {re.escape(str(trace))}:[0-9]+: {message}", err), err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert not (tmp_path / "out" / "summary.json").exists()


def _forge_recording(source: Path, target: Path, edit: Callable[[Lines], None]) -> None:
    """The recording with its /rei/trace lines edited (every other message as it was),
    written with mcap's own writer: what a hand-editor of the MCAP file would do."""
    with source.open("rb") as handle:
        reader = make_reader(handle)
        summary = reader.get_summary()
        assert summary is not None
        messages = list(reader.iter_messages(log_time_order=False))
    text = STORE.types[STRING]
    trace = [(i, json.loads(STORE.deserialize_cdr(m.data, STRING).data))
             for i, (_, c, m) in enumerate(messages) if c.topic == TRACE_TOPIC]
    lines = [x for _, x in trace]
    edit(lines)
    data = {i: bytes(STORE.serialize_cdr(text(json.dumps(x)), STRING))
            for (i, _), x in zip(trace, lines, strict=True)}
    with target.open("wb") as out:
        writer = Writer(out)
        writer.start(profile="ros2")
        schemas: dict[int, int] = {}
        channels: dict[int, int] = {}
        for i, (schema, channel, message) in enumerate(messages):
            if channel.id not in channels:
                sid = 0
                if schema is not None:
                    if schema.id not in schemas:
                        schemas[schema.id] = writer.register_schema(schema.name,
                                                                    schema.encoding, schema.data)
                    sid = schemas[schema.id]
                channels[channel.id] = writer.register_channel(
                    channel.topic, channel.message_encoding, sid, channel.metadata)
            writer.add_message(channels[channel.id], message.log_time,
                               data.get(i, message.data), message.publish_time,
                               message.sequence)
        writer.finish()  # type: ignore[no-untyped-call]


@pytest.mark.parametrize("forgery", ["task_fail deleted",
                                     "task_fail rewritten as task_success, end completed"])
def test_a_forged_recording_is_a_located_error_not_a_pass(
        timed_out: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str],
        forgery: str) -> None:
    edit, message = FORGERIES[forgery]
    forged = tmp_path / "forged.mcap"
    _forge_recording(timed_out / "recording.mcap", forged, edit)
    capsys.readouterr()
    status = rei(["replay", str(forged), "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert status == 2, err
    assert re.match(rf"^rei: error: {re.escape(str(forged))}: {TRACE_TOPIC} message [0-9]+: "
                    rf"{message}", err), err


def test_the_intact_run_still_fails_from_its_trace_and_its_recording(
        timed_out: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The audit refuses forgeries only: the real run replays to its live verdict (and its
    forged-recording writer is not what makes the forgeries fail)."""
    same = tmp_path / "same.mcap"
    _forge_recording(timed_out / "recording.mcap", same, lambda lines: None)
    for source in (timed_out / "trace.jsonl", timed_out / "recording.mcap", same):
        out = tmp_path / source.stem
        assert rei(["replay", str(source), "-o", str(out), "-q"]) == 1
        assert (out / "events.csv").read_bytes() == (timed_out / "events.csv").read_bytes()


# ---- the fuzzer: edits of mission events and the end line never make a FAIL pass ------------


def _edit(lines: Lines, data: st.DataObject) -> None:
    kind = data.draw(st.sampled_from(["delete", "rewrite", "cause", "outcome", "move",
                                      "scan"]), label="kind")
    events = _events(lines)
    if kind == "outcome":
        lines[-1]["outcome"] = data.draw(st.sampled_from(
            ["completed", "failed", "timeout", "error", "interrupted"]), label="outcome")
        return
    if kind == "scan":
        _scan(lambda s: s.update(data.draw(st.sampled_from(
            [{"angle_increment": 0.0}, {"angle_increment": 1.0}, {"ranges": [1.0, 1.0, 1.0]},
             {"angle_min": 0.0}, {"range_min": 9.0}]), label="scan")))(lines)
        return
    if not events:
        return
    i, k = data.draw(st.sampled_from(events), label="event")
    event = lines[i]["events"][k]
    if kind == "delete":
        del lines[i]["events"][k]
    elif kind == "rewrite":
        event["kind"] = data.draw(st.sampled_from(
            ["begin", "task_start", "task_success", "task_fail", "end"]), label="new kind")
        if event["kind"] in ("begin", "end"):
            event.update(task=None, index=None)
        elif event["task"] is None:
            event.update(task="at_the_wall", index=1)
        if event["kind"] != "task_fail":
            event["cause"] = ""
        elif not event["cause"]:
            event["cause"] = "aborted"
    elif kind == "cause" and event["kind"] == "task_fail":
        event["cause"] = data.draw(st.sampled_from(["aborted", "position", "heading", "cut"]))
    elif kind == "move":
        # the event moved to a later sample (its time with it): a success claimed elsewhere
        later = [j for j in range(i + 1, len(lines) - 1)]
        if later:
            j = data.draw(st.sampled_from(later), label="to")
            del lines[i]["events"][k]
            event["time"] = lines[j]["time"]
            lines[j].setdefault("events", []).append(event)


@settings(max_examples=50, deadline=None, derandomize=True, phases=(Phase.generate,),
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(data=st.data())
def test_no_edit_of_mission_events_or_outcome_turns_a_fail_into_a_pass(
        timed_out: Path, tmp_path_factory: pytest.TempPathFactory, data: st.DataObject) -> None:
    lines = _lines(timed_out)
    for _ in range(data.draw(st.integers(1, 3), label="edits")):
        _edit(lines, data)
    work = tmp_path_factory.mktemp("edit")
    trace = _save(lines, work / "trace.jsonl")
    try:
        summary = replay(trace, None, work / "out")
    except TraceError as exc:
        assert re.match(rf"^{re.escape(str(trace))}:[0-9]+: .*expected .*found", str(exc)), exc
        return
    assert judge(summary) != "pass"


def test_a_genuine_run_cut_in_its_settle_period_replays_as_it_ran(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Every task ended, then --duration cut the settle period: outcome 'timeout' is honest
    there (the tasks' outcomes stand) and replay gives the live run's verdict, not a refusal."""
    live, _ = run_into(EXAMPLES / "simple_wall" / "simple_wall.mission", tmp_path / "live",
                       duration=10.5)
    assert live.outcome == "timeout"
    # both tasks succeeded (at 0.1 s and 9.0 s) before the cut: it fell in the settle period
    assert (tmp_path / "live" / "events.csv").read_text().count("SIG_MISSION_TASK_SUCCESS") == 2
    capsys.readouterr()
    status = rei(["replay", str(tmp_path / "live" / "trace.jsonl"), "-o", str(tmp_path / "again")])
    assert status == 1, capsys.readouterr().err  # inconclusive, as the live run
    assert (tmp_path / "again" / "events.csv").read_text() == \
        (tmp_path / "live" / "events.csv").read_text()
    assert json.loads((tmp_path / "again" / "summary.json").read_text())["verdict"] == \
        judge(live)
