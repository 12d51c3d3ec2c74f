"""The one pass rule on real pybullet runs: a navigator that aborts every goal standing still
breaks no collision or speed requirement, yet `rei run` exits 1, summary.json says fail with
the executor's reason, and a campaign's JUnit shows the failure where CI looks."""

from __future__ import annotations

import csv
import json
from pathlib import Path

from lxml import etree

from rei.runtime.commands.cli import main
from rei.runtime.results import RunSummary, judge

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
SIMPLE_WALL = EXAMPLES / "simple_wall" / "simple_wall.mission"
ABORTS = "tests.robot.faulty:AbortsAtOnce"


def test_an_aborted_task_with_otherwise_green_requirements_fails_the_run(tmp_path: Path) -> None:
    status = main(["run", str(SIMPLE_WALL), "-o", str(tmp_path), "--controller", ABORTS,
                   "--quiet"])
    assert status == 1
    data = json.loads((tmp_path / "summary.json").read_text(encoding="utf-8"))
    assert data["verdict"] == "fail"
    summary = RunSummary.from_json(data)
    assert judge(summary) == "fail"
    verdicts = {v.requirement: v for v in summary.verdicts}
    goals = verdicts.pop("MISSION_GOALS_REACHED")
    assert goals.status == "fail"
    assert "aborted: no path to the goal" in goals.reason and goals.decided_at is not None
    # nothing else sees it: no collision, no speeding, and no people or headings here
    assert {v.status for v in verdicts.values()} <= {"pass", "not_applicable"}, verdicts


def test_the_reference_navigator_passes_the_same_mission(tmp_path: Path) -> None:
    assert main(["run", str(SIMPLE_WALL), "-o", str(tmp_path), "--quiet"]) == 0
    data = json.loads((tmp_path / "summary.json").read_text(encoding="utf-8"))
    assert data["verdict"] == "pass"


def test_a_campaign_reports_the_abort_in_junit_and_fails(tmp_path: Path) -> None:
    out = tmp_path / "campaign"
    status = main(["campaign", str(SIMPLE_WALL), "-o", str(out), "--repeat", "1",
                   "--workers", "1", "--controller", ABORTS])
    assert status == 1
    doc = etree.parse(str(out / "junit.xml")).getroot()
    failures = list(doc.iter("failure"))
    assert len(failures) == 1
    assert failures[0].getparent().get("name", "").startswith("MISSION_GOALS_REACHED")
    assert "aborted: no path to the goal" in failures[0].get("message", "")
    with open(out / "results.csv", encoding="utf-8", newline="") as handle:
        (row,) = csv.DictReader(handle)
    assert row["verdict"] == "fail" and row["failed_requirements"] == "MISSION_GOALS_REACHED"
    assert "aborted: no path to the goal" in row["failure"]
