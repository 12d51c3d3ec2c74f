"""Behaviour coverage of a campaign (rei.runtime.campaigns.coverage): which of the behaviours a
navigator owes its runs exercised, in the report, coverage.json and the terminal."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

from rei.runtime.campaigns import CampaignStore
from rei.runtime.campaigns.coverage import COVERAGE_JSON, behaviour_coverage, situation_coverage
from rei.runtime.campaigns.run_records import RunRecord
from rei.runtime.observation.model.situations import SITUATIONS
from rei.runtime.presentation.campaign_report import build_report
from rei.runtime.robot.behaviours import BEHAVIOURS
from tests.campaigns.records import write_campaign

TALLY = {"episodes": 2, "seconds": 1.5, "first": 3.0}


def with_behaviours(record: RunRecord, names: list[str]) -> RunRecord:
    assert record.summary is not None
    measurements = {**record.summary.measurements,
                    "behaviours": {name: dict(TALLY) for name in names}}
    return replace(record, summary=replace(record.summary, measurements=measurements))


def records_of(root: Path) -> list[RunRecord]:
    write_campaign(root)
    return list(CampaignStore.read(root)[2])


def test_coverage_counts_runs_episodes_and_the_behaviours_never_exercised(tmp_path: Path) -> None:
    records = records_of(tmp_path / "c")
    measured = [r for r in records if r.summary is not None]
    crashed = len(records) - len(measured)
    assert measured and crashed  # the example campaign has a run that left no summary
    marked = [with_behaviours(measured[0], ["recovery.backup", "goal_heading"]),
              with_behaviours(measured[1], ["goal_heading", "docking"])]
    coverage = behaviour_coverage(marked + measured[2:] + [r for r in records
                                                          if r.summary is None])
    rows = {r.name: r for r in coverage.rows}
    assert rows["goal_heading"].runs == 2 and rows["goal_heading"].episodes == 4
    assert rows["goal_heading"].seconds == 3.0
    assert rows["recovery.backup"].runs == 1
    assert rows["docking"].runs == 1  # a controller's own behaviour is kept, after the known
    assert [r.name for r in coverage.rows][-1] == "docking"
    assert coverage.exercised == 2
    assert set(coverage.never) == set(BEHAVIOURS) - {"recovery.backup", "goal_heading"}
    # the example summaries predate the measurement: they and the crashed run are unmeasured
    assert coverage.unmeasured == len(records) - 2
    assert "2 of" in coverage.line() and "never: recovery.replan," in coverage.line()


def test_situation_coverage_sums_the_situations_of_the_runs(tmp_path: Path) -> None:
    records = [r for r in records_of(tmp_path / "c") if r.summary is not None]
    assert records[0].summary is not None
    measured = [replace(records[0], summary=replace(records[0].summary, measurements={
        "situations": {"goal_behind": dict(TALLY)}}))]
    coverage = situation_coverage(measured + records[1:])
    assert coverage.exercised == 1 and "goal_behind" not in coverage.never
    assert coverage.unmeasured == len(records) - 1
    assert coverage.line().startswith("situation coverage: 1 of")


def test_the_report_writes_coverage_json_and_shows_the_table(tmp_path: Path) -> None:
    root = tmp_path / "c"
    write_campaign(root)
    outcome = build_report(root)
    data = json.loads((root / COVERAGE_JSON).read_text(encoding="utf-8"))
    assert data["format"] == "rei-coverage"
    behaviours, situations = data["behaviours"], data["situations"]
    assert behaviours["runs"] == situations["runs"] == len(outcome.records)
    assert behaviours["exercised"] == 0 and behaviours["never"] == list(BEHAVIOURS)
    assert situations["never"] == list(SITUATIONS)
    page = (root / "report.html").read_text(encoding="utf-8")
    assert 'id="coverage"' in page and "Never exercised:" in page and "Never met:" in page
    assert "recovery.backup" in page and "person_standing_on_route" in page
    assert "behaviour coverage: 0 of" in outcome.describe()
    assert "situation coverage: 0 of" in outcome.describe()
    first = (root / COVERAGE_JSON).read_bytes()
    build_report(root, html=False)
    assert (root / COVERAGE_JSON).read_bytes() == first
