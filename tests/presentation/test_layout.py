"""The campaign report and the run page laid out by a real browser (headless Chromium) at
both ends of the widths readers use, 800 and 1920 px, and measured in the DOM
(tests/presentation/measure_layout.js), not eyeballed (issue 27.2):

- no table header wider than its column, and no word of a header broken across lines (a
  name may wrap at its underscores, or stand rotated in a wide matrix);
- every text at WCAG AA contrast against what is behind it (4.5:1, 3:1 for large text),
  chart text included;
- no text below 11 px on screen: HTML text, SVG chart text at its drawn scale, and the
  raster maps never shown below 11/12 of their size (their text is drawn at 12 px).
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
from lxml import etree

from rei.runtime.campaigns import CampaignStore, RunResult
from rei.runtime.commands.cli import main
from rei.runtime.presentation.campaign_report import build_report
from rei.runtime.results import Verdict
from tests.campaigns.records import events_csv, example_plan, outcome_of, summary_for
from tests.conftest import chromium

WIDTHS = (800, 1920)
MEASURE = (Path(__file__).parent / "measure_layout.js").read_text(encoding="utf-8")
MISSION = Path(__file__).resolve().parents[2] / "examples" / "navigation" / "navigation.mission"
# The default .vepl's requirements: long names with underscores, the matrix's worst case.
REQUIREMENTS = ("GEOM_CLOSE_LASER_CORRECT", "GEOM_COLLISION_LASER_CORRECT", "MISSION_SIMPLE",
                "MISSION_SEQUENCE", "MISSION_SEQUENCE_CYCLE", "MISSION_WITH_HUMAN_TRAJECTORY",
                "MISSION_GOALS_REACHED", "GOAL_HEADING", "SPEED_LIMIT", "HUMAN_SLOW_ZONE",
                "NO_ROBOT_COLLISION", "SMOOTH_MOTION")


def _wide_campaign(root: Path) -> None:
    """The examples' campaign judged by twelve requirements (some failing, some not
    applicable), written through the real store."""
    plan = example_plan()
    with CampaignStore.open(root, plan, {"command": ["rei", "campaign", "examples"],
                                         "engine": {"engine": "local", "workers": 2}}) as store:
        for spec in plan.runs:
            kind = outcome_of(spec.run_id, spec.repeat)
            stem = Path(spec.mission_file).stem
            summary = summary_for(stem, f"{stem}_room", spec.seed, kind == "pass",
                                  10.0 + spec.repeat)
            verdicts = tuple(
                Verdict(name, "not_applicable" if i % 4 == 2 else
                        ("fail" if kind == "fail" and i % 3 == 0 else "pass"),
                        None, "a reason long enough to wrap in a narrow column of the table")
                for i, name in enumerate(REQUIREMENTS))
            summary = replace(summary, verdicts=verdicts)
            result = RunResult(spec.run_id, "ran", 0 if kind == "pass" else 1, 1.0,
                               summary.to_json(), "", {"events.csv": events_csv(summary)})
            store.record(spec, result, store.new_work_dir(spec.run_id))
        store.write_tables()
    build_report(root)


@pytest.fixture(scope="module")
def pages(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    base = tmp_path_factory.mktemp("layout")
    campaign = base / "campaign"
    _wide_campaign(campaign)
    run = base / "run"
    # A real run with a walking human (trajectory time labels on its map), cut short.
    status = main(["run", str(MISSION), "--controller", "teleop", "--duration", "12", "-o",
                   str(run), "--quiet"])
    assert status in (0, 1)
    return {"campaign": campaign / "report.html", "run": run / "report.html"}


def measure(page: Path, width: int, tmp_path: Path) -> dict[str, Any]:
    """Lay the page out at ``width`` px in Chromium and return what measure_layout.js saw."""
    copy = page.parent / f"measured-{width}.html"
    html = page.read_text(encoding="utf-8")
    copy.write_text(html.replace("</body>", f"<script>{MEASURE}</script></body>"),
                    encoding="utf-8")
    try:
        dom = chromium(copy, tmp_path, "--dump-dom", f"--window-size={width},1200",
                       "--virtual-time-budget=5000").stdout
    finally:
        copy.unlink()
    (report,) = etree.HTML(dom).xpath("//pre[@id='layout-report']/text()")
    result: dict[str, Any] = json.loads(report)
    return result


@pytest.mark.slow
@pytest.mark.parametrize("width", WIDTHS)
@pytest.mark.parametrize("name", ["campaign", "run"])
def test_pages_are_readable_at_800_and_1920_px(pages: dict[str, Path], name: str, width: int,
                                              tmp_path: Path) -> None:
    found = measure(pages[name], width, tmp_path)
    assert found["width"] == width
    assert found["headers"] >= 5 and found["svgTexts"] > 20  # the page was laid out in full
    assert found["overflowing"] == []
    assert found["brokenWords"] == []
    assert found["lowContrast"] == []
    assert found["smallText"] == []
    assert found["smallChartText"] == []
    assert found["shrunkImages"] == []
    assert found["minChartPx"] >= 11 and found["minContrast"] >= 4.5
    if name == "campaign":  # the distinct failures come first and fit the page's width
        assert found["firstSection"] == "clusters" and found["clusterRows"] >= 1
        assert found["clustersOverflow"] == 0


@pytest.mark.slow
def test_a_wide_matrix_rotates_its_headers(pages: dict[str, Path]) -> None:
    page = etree.HTML(pages["campaign"].read_text(encoding="utf-8"))
    (matrix,) = page.xpath("//table[@id='requirement-matrix']")
    assert "rotated" in matrix.get("class").split()
    headers = matrix.xpath(".//th[@class='requirement']")
    assert {th.get("title") for th in headers} == set(REQUIREMENTS)
    # the engine of the provenance reads as words, not as a Python dict
    engine = page.xpath("//th[text()='engine']/following-sibling::td/text()")
    assert engine == ["local (workers 2)"]

