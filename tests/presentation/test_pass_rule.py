"""One pass rule behind every consumer: judge(), summary.json, the results row, JUnit and
the report all say the same of the same run."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest
from lxml import etree

from rei.runtime.campaigns import CampaignStore, RunResult, plan_campaign
from rei.runtime.campaigns.results_table import record_row
from rei.runtime.campaigns.run_records import RunRecord, verdict_reason
from rei.runtime.presentation.campaign_report.build import build_report
from rei.runtime.presentation.junit import junit_xml
from rei.runtime.results import RESULTS_VERSION, Outcome, RunSummary, Verdict, judge
from tests.campaigns.records import EXAMPLES

ABORT = "aborted: no path to the goal"


def summary(outcome: Outcome, *statuses: str) -> RunSummary:
    verdicts = tuple(Verdict(f"R{i}", s, 3.0 if s == "fail" else None,  # type: ignore[arg-type]
                             f"reason {i}: {ABORT}" if s == "fail" else f"reason {i}",
                             ("goal",) if s == "fail" else ())
                     for i, s in enumerate(statuses))
    return RunSummary(RESULTS_VERSION, "m", "r", 1, "ctl", outcome, "why", 5.0, 0.0, {},
                      verdicts)


@pytest.mark.parametrize(("outcome", "statuses", "expected"), [
    ("completed", ("pass", "pass"), "pass"),
    ("completed", ("pass", "not_applicable"), "pass"),
    # a task failed or timed out but every requirement passed: the requirements decide (the
    # default .vepl's MISSION_GOALS_REACHED is what fails such a run, never a side rule)
    ("failed", ("pass",), "pass"),
    ("timeout", ("pass",), "pass"),
    ("completed", ("pass", "fail"), "fail"),
    ("completed", ("inconclusive", "pass"), "inconclusive"),
    ("completed", ("inconclusive", "fail"), "fail"),
    ("completed", ("not_applicable",), "inconclusive"),
    ("completed", (), "unjudged"),
    ("error", ("pass",), "error"),
    ("interrupted", ("pass",), "interrupted"),
])
def test_judge(outcome: Outcome, statuses: tuple[str, ...], expected: str) -> None:
    s = summary(outcome, *statuses)
    assert judge(s) == expected
    assert s.passed == (expected == "pass")
    data = s.to_json()
    assert data["verdict"] == expected
    assert RunSummary.from_json(data) == s


def _record(run_id: str, s: RunSummary | None, status: str = "ran") -> RunRecord:
    plan = plan_campaign([EXAMPLES / "simple_wall"], repeat=1, seed=1, duration=2.0)
    spec = plan.runs[0]
    return RunRecord(replace(spec, run_id=run_id), status,  # type: ignore[arg-type]
                     1, 2.0, "no summary" if s is None else "", s)


def test_junit_results_and_reasons_follow_the_rule() -> None:
    records = [_record("a.r00", summary("completed", "pass", "not_applicable")),
               _record("b.r00", summary("failed", "pass", "fail")),
               _record("c.r00", summary("completed", "pass", "inconclusive")),
               _record("d.r00", summary("error", "pass")),
               _record("e.r00", None, status="crashed")]
    assert [r.verdict for r in records] == ["pass", "fail", "inconclusive", "error", "error"]
    rows = [record_row(r) for r in records]
    assert [row["passed"] for row in rows] == [True, False, False, False, False]
    assert rows[1]["failed_requirements"] == "R1"
    assert ABORT in rows[1]["failure"] and rows[0]["failure"] == ""
    assert verdict_reason(records[3]).startswith("error:")
    doc = etree.fromstring(junit_xml(records, {r.spec.run_id: f"rerun {r.spec.run_id}"
                                               for r in records}))
    cases = doc.findall(".//testcase")
    failures = [c for c in cases if c.find("failure") is not None]
    assert {c.get("classname") for c in failures} == {"b.r00", "c.r00"}
    fail_text = next(c for c in failures if c.get("classname") == "b.r00").find("failure")
    assert fail_text is not None and ABORT in fail_text.get("message", "")
    assert "t=3 s" in fail_text.get("message", "") and "goal" in fail_text.get("message", "")
    inconclusive = next(c for c in failures if c.get("classname") == "c.r00").find("failure")
    assert inconclusive is not None and inconclusive.get("type") == "inconclusive"
    errors = [c for c in cases if c.find("error") is not None]
    assert {c.get("classname") for c in errors} == {"d.r00", "e.r00"}
    skipped = [c for c in cases if c.find("skipped") is not None]
    assert [c.get("classname") for c in skipped] == ["a.r00"]
    assert doc.get("failures") == "2" and doc.get("errors") == "2"
    # the wall time of each run is shared over its cases: the suite's time is the real time
    assert float(doc.get("time", "0")) == pytest.approx(2.0 * len(records))
    props = {p.get("name"): p.get("value") for p in cases[0].iter("property")}
    assert props["rerun"] == "rerun a.r00" and props["seed"] == str(records[0].spec.seed)


def test_the_report_shows_the_failed_requirement_and_reason(tmp_path: Path) -> None:
    plan = plan_campaign([EXAMPLES / "simple_wall"], repeat=2, seed=1, duration=2.0)
    with CampaignStore.open(tmp_path, plan, {"command": ["rei", "campaign"]}) as store:
        for spec, s in zip(plan.runs, (summary("completed", "pass"),
                                       summary("failed", "pass", "fail")), strict=True):
            work = store.new_work_dir(spec.run_id)
            store.record(spec, RunResult(spec.run_id, "ran", 0, 1.0, s.to_json(), ""), work)
    outcome = build_report(tmp_path)
    assert len(outcome.failed) == 1
    html = (tmp_path / "report.html").read_text(encoding="utf-8")
    assert ABORT in html and "R1" in html
    csv_text = (tmp_path / "results.csv").read_text(encoding="utf-8")
    assert "verdict" in csv_text.splitlines()[0]
