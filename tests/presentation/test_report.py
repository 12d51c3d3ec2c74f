"""The report of a campaign folder: thesis-shaped tables, JUnit XML, the HTML page (rendered in
real headless Chromium), and `rei report`."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from lxml import etree

from rei.runtime.campaigns import CampaignStore
from rei.runtime.commands.cli import main
from rei.runtime.presentation.campaign_report import build_report, execution_summary, signal_counts
from rei.runtime.presentation.campaign_report.tables import (
    group_success,
    group_success_table,
    mission_success,
)
from tests.campaigns.records import write_campaign
from tests.conftest import chromium


@pytest.fixture
def campaign(tmp_path: Path) -> Path:
    root = tmp_path / "campaign"
    write_campaign(root)
    return root


def test_execution_summary_has_the_shape_of_thesis_table_5(campaign: Path) -> None:
    _, _, records = CampaignStore.read(campaign)
    table = execution_summary(records)
    assert table.columns == ("Room", "Executions", "Mean execution time [s]",
                             "Median execution time [s]", "Mean utility", "Median utility",
                             "Max utility", "Min utility")
    rows = {row[0]: row for row in table.rows}
    # simple_wall: three passing repeats of 10, 11, 12 s, each worth 54.
    assert rows["simple_wall_room"] == ("simple_wall_room", 3, 11.0, 11.0, 54.0, 54.0, 54.0,
                                        54.0)
    # navigation: the second repeat failed a task (-100 and a TASK_FAIL signal).
    assert rows["navigation_room"][4:] == pytest.approx((62 / 3, 54.0, 54.0, -46.0))
    # small_dense crashed once: it counts as an execution without time or utility.
    assert rows["small_dense_room"][:4] == ("small_dense_room", 3, 11.5, 11.5)
    assert table.footer is not None and table.footer[:2] == ("Total", 12)


def test_signal_counts_have_the_shape_of_thesis_table_6(campaign: Path) -> None:
    _, _, records = CampaignStore.read(campaign)
    table = signal_counts(records)
    assert table.columns == ("Signal", "medium_sparse_room", "navigation_room",
                             "simple_wall_room", "small_dense_room", "Total")
    rows = {row[0]: row for row in table.rows}
    assert rows["SIG_MISSION_BEGIN"] == ("SIG_MISSION_BEGIN", 3, 3, 3, 2, 11)
    assert rows["SIG_MISSION_TASK_FAIL"] == ("SIG_MISSION_TASK_FAIL", 3, 1, 0, 0, 4)
    assert [r[0] for r in table.rows][:2] == ["SIG_MISSION_BEGIN", "SIG_MISSION_END"]


def test_success_rates_per_mission_and_group(campaign: Path) -> None:
    _, _, records = CampaignStore.read(campaign)
    flaky = sorted(r.key for r in mission_success(records) if r.flaky)
    assert flaky == ["navigation", "small_dense"]
    assert [(g.key, g.passed, g.runs) for g in group_success(records)] == [("examples", 7, 12)]
    table = group_success_table(records)
    assert table.columns[-1] == "Flaky missions"
    assert table.rows == (("examples", 12, 7, "58 %", "[32 %, 81 %]", 2),)


def test_junit_has_a_suite_per_mission_and_a_case_per_requirement(campaign: Path) -> None:
    outcome = build_report(campaign, html=False)
    assert not outcome.all_passed and len(outcome.failed) == 5
    doc = etree.parse(str(campaign / "junit.xml"))
    suites = doc.getroot().findall("testsuite")
    assert [s.get("name") for s in suites] == ["medium_sparse", "navigation", "simple_wall",
                                               "small_dense"]
    nav = suites[1]
    assert (nav.get("tests"), nav.get("failures"), nav.get("errors")) == ("6", "1", "0")
    (failure,) = nav.iter("failure")
    assert failure.get("message") == "all_tasks_succeed fail at t=11 s: task 2 timed out"
    assert "re-run: rei run " in (failure.text or "") and "--seed" in (failure.text or "")
    small = suites[3]
    (error,) = small.iter("error")
    assert error.get("type") == "crashed"
    assert (small.get("tests"), small.get("errors")) == ("5", "1")
    root = doc.getroot()
    assert (root.get("tests"), root.get("failures"), root.get("errors")) == ("23", "4", "1")


def test_report_command_rebuilds_everything_and_exits_3_on_a_run_error(campaign: Path) -> None:
    for name in ("results.csv", "results.parquet"):
        (campaign / name).unlink()
    assert main(["report", str(campaign)]) == 3  # small_dense's first run crashed
    for name in ("results.csv", "results.parquet", "junit.xml", "report.html"):
        assert (campaign / name).stat().st_size > 0


def test_report_of_a_passing_campaign_exits_zero(tmp_path: Path) -> None:
    from rei.runtime.campaigns import plan_campaign  # noqa: PLC0415
    from tests.campaigns.records import EXAMPLES  # noqa: PLC0415

    write_campaign(tmp_path, plan_campaign([EXAMPLES / "simple_wall"], repeat=2))
    assert main(["report", str(tmp_path), "--no-html"]) == 0


def test_report_refuses_a_folder_that_is_not_a_campaign(tmp_path: Path,
                                                        capsys: pytest.CaptureFixture[str]
                                                        ) -> None:
    assert main(["report", str(tmp_path)]) == 2
    assert "not a REI campaign folder" in capsys.readouterr().err


def test_html_is_self_contained_and_deterministic(campaign: Path, tmp_path: Path) -> None:
    build_report(campaign)
    first = (campaign / "report.html").read_text(encoding="utf-8")
    copy = tmp_path / "again" / "campaign"
    write_campaign(copy)
    build_report(copy)
    assert (copy / "report.html").read_text(encoding="utf-8") == first
    page = etree.HTML(first)
    (script,) = page.xpath("//script")  # only the matrix sorter, inline
    assert script.get("src") is None
    assert all(src.startswith("data:image/png;base64,") for src in page.xpath("//img/@src"))
    assert not page.xpath("//link[@rel='stylesheet']")
    headings = page.xpath("//h2/text()")
    # the distinct failures lead the report (issue 25.4)
    assert headings[:3] == ["Distinct failures", "Requirements per mission", "Missions"]
    for heading in ("Success rates", "Execution summary", "Signals", "Utility over time",
                    "What utilities mean", "Provenance"):
        assert heading in headings
    assert len(page.xpath("//div[@id='utility-plot']//*[local-name()='svg']")) == 1
    assert len(page.xpath("//div[@id='signal-plot']//*[local-name()='svg']")) == 1
    # the matrix: a row per mission, worst first; a column per requirement
    matrix = page.xpath("//table[@id='requirement-matrix']")[0]
    assert [th.text for th in matrix.xpath(".//thead//th")][:2] == ["Mission", "Runs passed"]
    rows = matrix.xpath(".//tbody/tr")
    assert [r.xpath("./td[1]/a/text()")[0] for r in rows] == [
        "medium_sparse", "navigation", "small_dense", "simple_wall"]
    assert rows[0].xpath("./td[2]/text()") == ["0/3"]
    # clusters: the three medium_sparse failures and navigation's one are one cluster
    clusters = page.xpath("//table[@id='failure-clusters']/tbody/tr")
    first_cluster = [td.xpath("string(.)") for td in clusters[0].xpath("./td")]
    assert first_cluster[0] == "all_tasks_succeed" and first_cluster[3] == "4"
    assert "task 2 timed out" in first_cluster[5]
    assert any("crashed" in c.xpath("string(.)") for c in clusters)
    # each with its leading signals and the command that replays its smallest reproducer
    assert first_cluster[6] == "SIG_GEOM_CLOSE_TRANSIT_FAR → SIG_MISSION_TASK_SUCCESS → " \
                               "SIG_MISSION_END"
    assert first_cluster[7].startswith("rei run ") and "--seed" in first_cluster[7]
    # a collapsed section per mission: each run's verdict, reason and re-run command
    sections = page.xpath("//details")
    assert len(sections) == 4
    assert len(page.xpath("//details//tr[starts-with(@id, 'run-')]")) == 12
    assert "rei run " in "".join(page.xpath("//details//code/text()"))
    assert len(page.xpath("//details//figure[@class='map']/img")) == 5


def _chromium(campaign: Path, tmp_path: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return chromium(campaign / "report.html", tmp_path, *args)


@pytest.mark.slow
def test_report_renders_in_headless_chromium(campaign: Path, tmp_path: Path) -> None:
    build_report(campaign)
    dom = _chromium(campaign, tmp_path, "--dump-dom").stdout
    page = etree.HTML(dom)
    assert page.xpath("//h1/text()") == ["REI campaign: 4 missions × 3 repeats"]
    assert page.xpath("//table[@id='requirement-matrix']")
    assert page.xpath("//table[@id='failure-clusters']")
    shot = tmp_path / "report.png"
    _chromium(campaign, tmp_path, f"--screenshot={shot}", "--window-size=1400,2000")
    data = shot.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    assert int.from_bytes(data[16:20], "big") == 1400  # IHDR width: the page was laid out
    assert len(data) > 50_000  # a blank page compresses to a few kB; this one has content
