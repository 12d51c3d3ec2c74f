"""The page of one run (report.html beside events.csv), after a real `rei run` of the teleop
robot driving into the simple_wall example's wall: verdict, requirement rows, timeline,
distances with both thresholds, speed and map; rendered in real headless Chromium; the same
bytes for the same folder; written by `rei replay` too; linked from the campaign report."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from lxml import etree

from rei.runtime.campaigns import CampaignStore
from rei.runtime.commands.cli import main
from rei.runtime.presentation.campaign_report import build_report
from rei.runtime.presentation.campaign_report.html import run_page_link
from rei.runtime.presentation.run_page.rendering import write_run_page
from rei.runtime.presentation.run_page.run_data import thin_extremes
from tests.campaigns.records import write_campaign
from tests.conftest import chromium

MISSION = Path(__file__).resolve().parents[2] / "examples" / "simple_wall" / "simple_wall.mission"


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One real run shared by the module's tests (a few seconds of pybullet)."""
    out = tmp_path_factory.mktemp("run") / "wall"
    status = main(["run", str(MISSION), "--controller", "teleop", "-o", str(out), "--quiet"])
    assert status == 1  # the teleop robot hits the wall: requirements fail
    return out


def _page(run_dir: Path) -> etree._Element:
    return etree.HTML((run_dir / "report.html").read_text(encoding="utf-8"))


def _svg_text(page: etree._Element, div: str) -> str:
    (svg,) = page.xpath(f"//div[@id='{div}']/*[local-name()='svg']")
    return "".join(svg.itertext())


@pytest.mark.slow
def test_run_writes_its_page_with_the_verdict_and_every_requirement(run_dir: Path) -> None:
    page = _page(run_dir)
    summary = json.loads((run_dir / "summary.json").read_text(encoding="utf-8"))
    (verdict,) = page.xpath("//div[@id='verdict']")
    assert verdict.text == "FAIL" and "fail" in verdict.get("class").split()
    assert page.xpath("//dd[@id='controller']/text()") == ["teleop"]
    assert page.xpath("//dd[@id='room']/text()") == [summary["room"]]
    assert "failed" in "".join(page.xpath("//dd[@id='outcome']//text()"))
    rows = page.xpath("//table[@id='verdicts']/tbody/tr")
    assert [r.get("data-requirement") for r in rows] == [v["requirement"]
                                                          for v in summary["verdicts"]]
    status = {r.get("data-requirement"): r.xpath("td[@class='status']/text()")[0] for r in rows}
    assert status["NO_ROBOT_COLLISION"] == "fail"
    assert status["GOAL_HEADING"] == "not applicable"
    failed = {r.get("data-requirement") for r in rows if "status-fail" in r.get("class")}
    assert failed == {v["requirement"] for v in summary["verdicts"] if v["status"] == "fail"}
    decided = next(v for v in summary["verdicts"] if v["requirement"] == "NO_ROBOT_COLLISION")
    simple = next(r for r in rows if r.get("data-requirement") == "NO_ROBOT_COLLISION")
    assert [td.text for td in simple.xpath("td")][2:4] == [f"{decided['decided_at']:g} s",
                                                          "wall_e"]
    # self-contained: no scripts, no external style sheet, images inline
    assert page.xpath("//script") == [] and not page.xpath("//link[@rel='stylesheet']")
    assert all(src.startswith("data:image/png;base64,") for src in page.xpath("//img/@src"))


@pytest.mark.slow
def test_the_page_has_the_timeline_distances_speed_and_map(run_dir: Path) -> None:
    page = _page(run_dir)
    assert page.xpath("//h2/text()") == ["Requirements", "Timeline", "Distances", "Speed",
                                         "Map"]
    timeline = _svg_text(page, "timeline-plot")
    for word in ("MISSION_BEGIN", "GEOM_CLOSE_TRANSIT_COLLISION", "total utility",
                 "simulation time [s]", "#1 at_the_wall"):
        assert word in timeline
    events = [[td.xpath("string()") for td in tr.xpath("td")]
              for tr in page.xpath("//table[@id='mission-events']/tbody/tr")]
    assert [e[1] for e in events] == ["mission began", "task started", "task succeeded",
                                      "task started", "task failed", "mission ended"]
    assert events[4][3].startswith("outside tolerance")
    distance = _svg_text(page, "distance-plot")
    assert "CLOSE threshold (0.25 m)" in distance
    assert "COLLISION threshold (0.02 m)" in distance
    assert "nearest obstacle (walls, objects)" in distance and "nearest human" not in distance
    assert "footprint distance [m]" in distance and "NO_ROBOT_COLLISION" in distance
    speed = _svg_text(page, "speed-plot")
    assert "driven (ground truth)" in speed and "limit (0.26 m/s)" in speed
    assert "speed [m/s]" in speed
    (image,) = page.xpath("//img[@id='map-image']")
    assert image.get("alt").startswith("map of the run from above")
    failed = [r for r in page.xpath("//table[@id='verdicts']/tbody/tr")
              if "status-fail" in r.get("class")]
    assert f"{len(failed)} requirement(s) failed" in image.get("alt")
    ids = set(page.xpath("//@id"))
    for div in ("timeline-plot", "distance-plot", "speed-plot"):
        assert page.xpath(f"//div[@id='{div}']/@aria-label")
        # every marker and clip reference resolves (ids are renamed for stable bytes)
        svg = etree.tostring(page.xpath(f"//div[@id='{div}']")[0], encoding="unicode")
        references = set(re.findall(r'(?:href="#|url\(#)([^")]+)', svg))
        assert references and references <= ids


@pytest.mark.slow
def test_same_folder_same_bytes(run_dir: Path, tmp_path: Path) -> None:
    written = (run_dir / "report.html").read_bytes()
    assert write_run_page(run_dir).read_bytes() == written
    copy = tmp_path / "copy"
    shutil.copytree(run_dir, copy)
    (copy / "report.html").unlink()
    assert write_run_page(copy).read_bytes() == written


@pytest.mark.slow
def test_replay_writes_the_page_and_no_monitor_does_not(run_dir: Path, tmp_path: Path) -> None:
    out = tmp_path / "replayed"
    assert main(["replay", str(run_dir / "trace.jsonl"), "-o", str(out)]) == 1
    page = _page(out)
    assert page.xpath("//div[@id='verdict']/text()") == ["FAIL"]
    assert page.xpath("//img[@id='map-image']")  # the world beside the trace gives the map
    bare = tmp_path / "bare"
    assert main(["run", str(MISSION), "--controller", "teleop", "-o", str(bare), "--quiet",
                 "--no-monitor", "--duration", "2"]) == 0
    assert (bare / "trace.jsonl").is_file() and not (bare / "report.html").exists()


def test_a_specification_without_signals_draws_its_page_without_a_warning(
        run_dir: Path, tmp_path: Path) -> None:
    # No signal lane made matplotlib warn about identical y limits (warnings are errors here).
    vepl = tmp_path / "quiet.vepl"
    vepl.write_text("specification quiet\nquery near() { laser_min < 0.1 }\n", encoding="utf-8")
    out = tmp_path / "replayed"
    assert main(["replay", str(run_dir / "trace.jsonl"), "--vepl", str(vepl), "-o", str(out),
                 "--quiet"]) == 1  # nothing to judge: unjudged is never a pass
    assert (out / "report.html").is_file()


@pytest.mark.slow
def test_campaign_report_links_a_failed_run_to_its_page(run_dir: Path, tmp_path: Path
                                                        ) -> None:
    root = tmp_path / "campaign"
    write_campaign(root)
    _, _, records = CampaignStore.read(root)
    failed = next(r for r in records if not r.passed)
    passed = next(r for r in records if r.passed)
    shutil.copy(run_dir / "report.html", root / "runs" / failed.spec.run_id / "report.html")
    href = run_page_link(root, failed)
    assert href == f"runs/{failed.spec.run_id}/report.html"
    assert run_page_link(root, passed) is None
    build_report(root)
    campaign = etree.HTML((root / "report.html").read_text(encoding="utf-8"))
    assert campaign.xpath("//a[@class='run-page']/@href") == [href]


def test_thinning_keeps_a_short_dip_into_collision() -> None:
    time = np.arange(100_000) * 0.01
    value = np.full(100_000, 2.0)
    value[54_321] = -0.01  # one sample of contact
    thinned = thin_extremes(time, value, max_points=2000)
    assert len(thinned.value) <= 2000
    assert thinned.value.min() == -0.01 and thinned.time[thinned.value.argmin()] == 543.21


def _chromium(page: Path, tmp_path: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return chromium(page, tmp_path, *args)


@pytest.mark.slow
def test_run_page_renders_in_headless_chromium_at_1400_px(run_dir: Path, tmp_path: Path
                                                          ) -> None:
    page = run_dir / "report.html"
    dom = etree.HTML(_chromium(page, tmp_path, "--dump-dom").stdout)
    assert dom.xpath("//div[@id='verdict']/text()") == ["FAIL"]
    shot = tmp_path / "run-page.png"
    _chromium(page, tmp_path, f"--screenshot={shot}", "--window-size=1400,3400")
    data = shot.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    assert int.from_bytes(data[16:20], "big") == 1400  # IHDR width: the page was laid out
    assert len(data) > 100_000  # a blank page compresses to a few kB; this one has plots


@pytest.mark.slow
def test_the_map_draws_the_goals_when_the_trace_carries_the_mission_facts(run_dir: Path
                                                                          ) -> None:
    from dataclasses import replace  # noqa: PLC0415

    from rei.runtime.messages import GoalFacts, MissionFacts  # noqa: PLC0415
    from rei.runtime.presentation.maps import (  # noqa: PLC0415
        mission_from_facts,
        world_from_manifest,
    )
    from rei.runtime.presentation.run_page import run_plots  # noqa: PLC0415
    from rei.runtime.presentation.run_page.run_data import (  # noqa: PLC0415
        read_manifest,
        read_series,
    )

    manifest = read_manifest(run_dir, None)
    assert manifest is not None
    world = world_from_manifest(manifest)
    assert [w.name for w in world.walls] == [w.name for w in manifest.walls]
    facts = MissionFacts((GoalFacts("start_place", 0.0, 0.0, None, 0.25, 0.5, 60.0),
                          GoalFacts("at_the_wall", 2.0, 0.0, 0.0, 0.25, 0.5, 60.0)),
                         1, 120.0, 0.26, 1.82, None)
    mission = mission_from_facts("to_the_wall", world, facts)
    assert [(g.name, g.floor) for g in mission.goals] == [("start_place", "start"),
                                                          ("at_the_wall", "front")]
    series = replace(read_series(run_dir / "trace.jsonl", manifest), facts=facts)
    with_goals = run_plots.run_map(world, mission, series, [], "with goals")
    without = run_plots.run_map(world, None, series, [], "with goals")
    assert with_goals.startswith("data:image/png;base64,") and with_goals != without
