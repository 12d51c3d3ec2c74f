"""Which runs get their page (`rei run --page`, `rei campaign --pages`, `rei page DIR`): the full
page for a run that did not pass, a brief one for a run that passed under ``failed``, none under
``none``; `rei page` completes a brief page into the bytes `--page all` writes, and the campaign
report says which of its links are brief. Real runs of the simple_wall example."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from lxml import etree

from rei.runtime.campaigns import CampaignError
from rei.runtime.commands.cli import main
from rei.runtime.presentation.run_page.rendering import (
    BRIEF_MARK,
    PAGE,
    page_is_full,
    write_run_page,
)
from rei.runtime.results import RunSummary, judge
from tests.conftest import chromium

MISSION = Path(__file__).resolve().parents[2] / "examples" / "simple_wall" / "simple_wall.mission"

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """The reference robot passes simple_wall (with --page failed and --page all); teleop
    drives into the wall and fails (with --page failed)."""
    root = tmp_path_factory.mktemp("runs")
    found = {}
    for name, controller, page, expected in (("pass-failed", "reference", "failed", 0),
                                             ("pass-all", "reference", "all", 0),
                                             ("fail-failed", "teleop", "failed", 1)):
        out = root / name
        status = main(["run", str(MISSION), "--controller", controller, "-o", str(out),
                       "--page", page, "--quiet"])
        assert status == expected, name
        found[name] = out
    return found


def _page(folder: Path) -> etree._Element:
    return etree.HTML((folder / PAGE).read_text(encoding="utf-8"))


def test_a_passing_run_gets_the_brief_page_under_failed(runs: dict[str, Path]) -> None:
    brief = _page(runs["pass-failed"])
    assert brief.xpath("//meta[@name='rei-page']/@content") == ["brief"]
    assert brief.xpath("//div[@id='verdict']/text()") == ["PASS"]
    assert brief.xpath("//table[@id='verdicts']/tbody/tr")  # the requirements are there
    assert brief.xpath("//*[local-name()='svg']") == [] and brief.xpath("//img") == []
    assert "rei page" in "".join(brief.xpath("//p[@id='brief-note']//text()"))
    assert not page_is_full(runs["pass-failed"])
    # the same run under --page all: the full page, plots and map
    full = _page(runs["pass-all"])
    assert full.xpath("//meta[@name='rei-page']") == []
    assert full.xpath("//div[@id='timeline-plot']") and full.xpath("//img[@id='map-image']")
    assert page_is_full(runs["pass-all"])


def test_a_failing_run_gets_the_full_page_under_failed(runs: dict[str, Path]) -> None:
    page = _page(runs["fail-failed"])
    assert page.xpath("//div[@id='verdict']/text()") == ["FAIL"]
    assert BRIEF_MARK.encode() not in (runs["fail-failed"] / PAGE).read_bytes()
    assert page.xpath("//h2/text()") == ["Requirements", "Timeline", "Distances", "Speed",
                                         "Map"]


def test_rei_page_completes_a_brief_page_into_the_full_pages_bytes(
        runs: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = tmp_path / "run"
    shutil.copytree(runs["pass-failed"], folder)
    assert main(["page", str(folder)]) == 0
    assert (folder / PAGE).read_bytes() == (runs["pass-all"] / PAGE).read_bytes()
    before = (folder / PAGE).stat().st_mtime_ns
    assert main(["page", str(folder)]) == 0  # already full: left as it is
    assert (folder / PAGE).stat().st_mtime_ns == before
    assert capsys.readouterr().out.splitlines() == [
        "rei page: 1 page(s) drawn, 0 already full", "rei page: 0 page(s) drawn, 1 already full"]


def test_rei_page_refuses_a_folder_that_is_no_run_and_no_campaign(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["page", str(tmp_path / "missing")]) == 2
    assert main(["page", str(tmp_path)]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err == [f"rei: error: {tmp_path / 'missing'}: expected a run folder or a campaign "
                   f"folder, found nothing",
                   f"rei: error: {tmp_path}: expected a run folder (with summary.json) or a "
                   f"campaign folder (with campaign.json), found neither"]


def test_no_page_under_none_and_an_unknown_policy_is_refused(
        runs: dict[str, Path], tmp_path: Path) -> None:
    folder = tmp_path / "run"
    shutil.copytree(runs["pass-all"], folder)
    (folder / PAGE).unlink()
    assert write_run_page(folder, policy="none") is None
    assert not (folder / PAGE).exists()
    with pytest.raises(ValueError, match="expected one of all, failed, none, found 'some'"):
        write_run_page(folder, policy="some")
    with pytest.raises(SystemExit):  # argparse: exit 2 with its usage line
        main(["run", str(MISSION), "-o", str(tmp_path / "x"), "--page", "some"])


def test_a_campaign_draws_brief_pages_says_so_and_rei_page_completes_them(
        tmp_path: Path) -> None:
    out = tmp_path / "campaign"
    assert main(["campaign", str(MISSION), "-o", str(out), "--repeat", "2", "--workers", "2",
                 "-q"]) == 0
    folders = sorted((out / "runs").iterdir())
    assert len(folders) == 2
    assert all(judge(RunSummary.from_json(json.loads((f / "summary.json").read_text())))
               == "pass" for f in folders)
    # the default --pages failed: brief pages for these passing runs
    assert not any(page_is_full(f) for f in folders)
    report = etree.HTML((out / "report.html").read_text(encoding="utf-8"))
    note = "".join(report.xpath("//p[@id='page-note']//text()"))
    assert "2 of them are brief" in note and "rei page" in note
    assert main(["page", str(out)]) == 0
    assert all(page_is_full(f) for f in folders)
    assert main(["report", str(out)]) in (0, 1)
    report = etree.HTML((out / "report.html").read_text(encoding="utf-8"))
    assert report.xpath("//p[@id='page-note']") == []


def test_the_brief_page_renders_in_headless_chromium(runs: dict[str, Path],
                                                     tmp_path: Path) -> None:
    dom = etree.HTML(chromium(runs["pass-failed"] / PAGE, tmp_path, "--dump-dom").stdout)
    assert dom.xpath("//div[@id='verdict']/text()") == ["PASS"]
    assert dom.xpath("//p[@id='brief-note']") and dom.xpath("//table[@id='verdicts']")


def test_campaign_error_names_the_option() -> None:
    from rei.runtime.campaigns import LocalEngine  # noqa: PLC0415

    with pytest.raises(CampaignError, match="--pages: expected one of all, failed, none"):
        LocalEngine(1, pages="brief")
