"""Robustness margins: negative exactly when the requirement fails, none where it has no
natural margin or was not judged, and falling as a run is pushed towards failure (a closer
person, a faster robot near people, a slower or longer way to the goal). Synthetic streams
(tests/observation/test_default_requirements.py's); real pybullet runs in test_margin_runs."""

from __future__ import annotations

from pathlib import Path

import pytest

from rei.lang.vepl.document import DEFAULT_VEPL
from rei.runtime.messages import MissionEvent
from rei.runtime.observation.evaluator.margins import RULES, smallest_margin
from rei.runtime.observation.monitor import MonitorSink
from rei.runtime.results import Verdict
from tests.observation.helpers import monitor
from tests.observation.streams import human, wall
from tests.observation.test_default_requirements import (
    FAR_WALL,
    Tick,
    driving,
    facts,
    mission_events,
    run,
    stream,
    with_events,
)


def _signs_agree(verdicts: dict[str, Verdict]) -> None:
    for v in verdicts.values():
        if v.margin is not None:
            assert (v.margin < 0) == (v.status == "fail"), v
            assert v.status in ("pass", "fail")
            assert v.margin_unit == RULES[v.requirement].unit


def test_a_clean_run_has_non_negative_margins_and_none_where_not_judged(tmp_path: Path) -> None:
    verdicts, _ = run(tmp_path, FAR_WALL, driving(0.0, 1.0, 12, 0.2))
    _signs_agree(verdicts)
    # not applicable: no margin, never a number standing in for one
    for name in ("MISSION_WITH_HUMAN_TRAJECTORY", "HUMAN_SLOW_ZONE", "GOAL_HEADING"):
        assert verdicts[name].status == "not_applicable" and verdicts[name].margin is None
    # decided by event patterns: no natural margin
    for name in ("MISSION_SEQUENCE", "SMOOTH_MOTION", "GEOM_CLOSE_LASER_CORRECT"):
        assert verdicts[name].margin is None
    assert verdicts["SPEED_LIMIT"].margin == pytest.approx((0.27 - 0.2) / 0.27)
    # the stream drives on for one tick (0.1 s at 0.2 m/s) after the success: 0.02 m of 0.1
    assert verdicts["SETTLE"].margin == pytest.approx(0.08)
    # a goal reached in 1.0 s of its 60 s timeout
    assert verdicts["MISSION_GOALS_REACHED"].margin == pytest.approx(1 - 1.0 / 60)
    # the wall's face at 4.5 m: the robot never closed in on anything within 0.5 m
    assert verdicts["NO_ROBOT_COLLISION"].margin == pytest.approx(0.48)


def test_failures_have_negative_margins(tmp_path: Path) -> None:
    slow = facts(speed_limit=0.1)
    verdicts, _ = run(tmp_path / "speed", FAR_WALL, driving(0.0, 1.0, 12, 0.2), slow)
    assert verdicts["SPEED_LIMIT"].status == "fail"
    assert verdicts["SPEED_LIMIT"].margin == pytest.approx((0.11 - 0.2) / 0.11)
    near_wall = [wall("w", 1.0, 0.0)]
    crash, _ = run(tmp_path / "wall", near_wall, driving(0.0, 0.36, 10, 0.1))
    assert crash["NO_ROBOT_COLLISION"].status == "fail"
    assert crash["NO_ROBOT_COLLISION"].margin is not None
    assert crash["NO_ROBOT_COLLISION"].margin < 0
    aborted, _ = run(tmp_path / "abort", FAR_WALL, driving(0.0, 1.0, 12, 0.2),
                     fail=("aborted", "aborted: no path"))
    assert aborted["MISSION_GOALS_REACHED"].margin == -1.0
    for verdicts_ in (verdicts, crash, aborted):
        _signs_agree(verdicts_)


def test_the_margin_to_a_person_falls_as_the_person_comes_closer(tmp_path: Path) -> None:
    margins = []
    # robot front edge at x + 0.14 stops at 1.04; a person of radius 0.25 ever closer
    for i, x in enumerate((2.0, 1.6, 1.4, 1.3, 1.25)):
        verdicts, _ = run(tmp_path / str(i), [human("alice", x, 0.0)],
                          driving(0.0, 0.9, 12, 0.1))
        _signs_agree(verdicts)
        v = verdicts["MISSION_WITH_HUMAN_TRAJECTORY"]
        assert v.margin is not None
        margins.append(v.margin)
    assert margins == sorted(margins, reverse=True) and len(set(margins)) == len(margins)
    assert margins[0] > 0 > margins[-1]


def test_the_slow_zone_margin_falls_as_the_robot_drives_faster_near_a_person(
        tmp_path: Path) -> None:
    margins = []
    statuses = []
    for i, v in enumerate((0.05, 0.1, 0.15, 0.2, 0.25)):
        verdicts, _ = run(tmp_path / str(i), [human("alice", 1.6, 0.0)],
                          driving(0.0, 0.9, 12, v))
        _signs_agree(verdicts)
        margins.append(verdicts["HUMAN_SLOW_ZONE"].margin)
        statuses.append(verdicts["HUMAN_SLOW_ZONE"].status)
    assert statuses == ["pass", "pass", "pass", "fail", "fail"]
    assert margins == pytest.approx([0.11, 0.06, 0.01, -0.04, -0.09])
    # never nearer than slow_zone: the requirement judged nothing there, so no margin
    far, _ = run(tmp_path / "far", [human("bob", 4.0, 0.0)], driving(0.0, 0.9, 12, 0.25))
    assert far["HUMAN_SLOW_ZONE"].status == "pass" and far["HUMAN_SLOW_ZONE"].margin is None


def test_the_goal_margin_falls_as_the_navigator_gets_slower(tmp_path: Path) -> None:
    margins = []
    for n in (12, 30, 60):  # the same 1 m at 10 Hz in 1, 2.8 and 5.8 s
        verdicts, _ = run(tmp_path / str(n), FAR_WALL, driving(0.0, 1.0, n, 1.0 / (n / 10)))
        _signs_agree(verdicts)
        margins.append(verdicts["MISSION_GOALS_REACHED"].margin)
    assert margins == sorted(margins, reverse=True) and len(set(margins)) == 3


def test_settle_margin_falls_as_the_robot_rolls_on_after_its_goal(tmp_path: Path) -> None:
    margins = []
    for roll in (0.0, 0.05, 0.3):
        ticks = driving(0.0, 1.0, 12, 0.2)
        after = [Tick((1.0 + roll * (i + 1) / 10, 0.0, 0.0), (roll, 0.0, 0.0), (roll, 0.0))
                 for i in range(10)]
        # the task succeeds at tick 11; the end comes after the roll
        events = {0: (MissionEvent("begin", 0.0), MissionEvent("task_start", 0.0, "g0", 0)),
                  11: (MissionEvent("task_success", 1.1, "g0", 0),),
                  21: (MissionEvent("end", 2.1),)}
        all_ticks = [Tick(t.pose, t.twist, t.cmd, t.objects, events.get(i, ()))
                     for i, t in enumerate(ticks + after)]
        h, samples = stream(FAR_WALL, all_ticks)
        _, result = monitor(h, samples, tmp_path / str(roll))
        verdicts = {v.requirement: v for v in result.verdicts}
        _signs_agree(verdicts)
        margins.append(verdicts["SETTLE"].margin)
    assert margins == sorted(margins, reverse=True) and margins[-1] < 0


def test_a_renamed_or_changed_requirement_gets_no_margin(tmp_path: Path) -> None:
    text = DEFAULT_VEPL.read_text(encoding="utf-8")
    text = text.replace("requirement SETTLE ", "requirement MY_SETTLE ")
    text = text.replace("max_path_ratio = 1.5 ", "max_path_ratio = 1.2 ")
    vepl = tmp_path / "mine.vepl"
    vepl.write_text(text, encoding="utf-8")
    ticks = driving(0.0, 1.0, 12, 0.2)
    h, samples = stream(FAR_WALL, with_events(ticks, mission_events(len(ticks))))
    sink = MonitorSink(vepl, tmp_path / "out")
    sink.start(h)
    for s in samples:
        sink.feed(s)
    sink.finish(samples[-1].time, "completed", "")
    assert sink.result is not None
    verdicts = {v.requirement: v for v in sink.result.verdicts}
    assert verdicts["MY_SETTLE"].status == "pass" and verdicts["MY_SETTLE"].margin is None
    # a changed parameter keeps the requirement: its margin reads the user's threshold
    assert verdicts["SPEED_LIMIT"].margin is not None
    assert smallest_margin(tuple(verdicts.values())) is not None


def test_margins_reach_the_results_row_junit_and_summary_json() -> None:
    from dataclasses import replace as with_  # noqa: PLC0415

    from lxml import etree  # noqa: PLC0415

    from rei.runtime.campaigns import plan_campaign  # noqa: PLC0415
    from rei.runtime.campaigns.results_table import record_row  # noqa: PLC0415
    from rei.runtime.campaigns.run_records import RunRecord  # noqa: PLC0415
    from rei.runtime.presentation.junit import junit_xml  # noqa: PLC0415
    from rei.runtime.results import RESULTS_VERSION, RunSummary  # noqa: PLC0415
    from tests.conftest import EXAMPLES  # noqa: PLC0415

    verdicts = (Verdict("SPEED_LIMIT", "fail", 2.0, "too fast", (), -0.25, "fraction"),
                Verdict("SETTLE", "pass", 9.0, "stayed", (), 0.08, "m"),
                Verdict("HUMAN_SLOW_ZONE", "not_applicable", None, "no people"),
                Verdict("SMOOTH_MOTION", "pass", 9.0, "no weaving"))
    summary = RunSummary(RESULTS_VERSION, "m", "r", 1, "ctl", "completed", "", 9.0, 0.0, {},
                         verdicts)
    data = summary.to_json()
    assert [v["margin"] for v in data["verdicts"]] == [-0.25, 0.08, None, None]
    assert RunSummary.from_json(data) == summary
    spec = plan_campaign([EXAMPLES / "simple_wall"], repeat=1, seed=1, duration=2.0).runs[0]
    record = RunRecord(with_(spec, run_id="a.r00"), "ran", 1, 2.0, "", summary)
    row = record_row(record)
    assert row["smallest_margin"] == -0.25
    assert row["margin:SPEED_LIMIT"] == -0.25 and row["margin:SETTLE"] == 0.08
    assert row["margin:HUMAN_SLOW_ZONE"] is None and "margin:SMOOTH_MOTION" not in row
    doc = etree.fromstring(junit_xml([record], {"a.r00": "rerun"}))
    margins = {c.get("name", "").split(" [")[0]: p.get("value") for c in doc.iter("testcase")
               for p in c.iter("property") if p.get("name") == "margin"}
    assert margins == {"SPEED_LIMIT": "-0.25 fraction", "SETTLE": "0.08 m"}
