"""The report items issue 27 listed, one test each: the distance axis ends where its label
says, every repeat of a room has its own line style in the utility plot, the Repeats column
is never empty, the engine's provenance reads as words, and a mission that passed on every
run says why its interval is wide instead of sounding like a warning."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
from lxml import etree

from rei.runtime.campaigns import CampaignStore
from rei.runtime.campaigns.folder_reader import load_campaign
from rei.runtime.campaigns.stats import SuccessRate, judge_mission
from rei.runtime.presentation.campaign_report.campaign_plots import utility_over_time
from rei.runtime.presentation.campaign_report.html import _setting
from rei.runtime.presentation.campaign_report.tables import mission_success, success_table
from rei.runtime.presentation.run_page.run_data import Series, Thresholds
from rei.runtime.presentation.run_page.run_plots import DISTANCE_AXIS_MIN, distance_axis, distances
from tests.campaigns.records import write_campaign


def test_the_distance_axis_ends_where_its_label_says() -> None:
    far = np.array([3.0, 2.0, 0.4, 0.1, 0.3, 2.5])  # starts 3 m away: above the cut
    low, top, cut = distance_axis([far], 0.25)
    assert cut and top == DISTANCE_AXIS_MIN and low == 0.0
    time = np.linspace(0.0, 5.0, len(far))
    series = type("S", (), {"obstacle": Series(time, far), "human": None, "end": 5.0})()
    svg = distances(series, Thresholds(0.25, 0.02, "test"), [])  # type: ignore[arg-type]
    assert svg is not None
    label = " ".join(etree.fromstring(svg.encode()).itertext())
    assert "axis ends at 1.5 m" in label
    # Close to everything: no cut, the axis just above the farthest value.
    low, top, cut = distance_axis([np.array([0.2, 0.5, 0.9])], 0.25)
    assert not cut and 0.9 < top < 1.0


def _line_styles(svg: str) -> list[str]:
    """stroke colour + dash pattern of every drawn line of a matplotlib SVG."""
    root = etree.fromstring(svg.encode())
    styles = []
    for group in root.iter("{http://www.w3.org/2000/svg}g"):
        if (group.get("id") or "").startswith("line2d_"):
            for path in group.iter("{http://www.w3.org/2000/svg}path"):
                style = path.get("style") or ""
                stroke = re.search(r"stroke: ?([^;]+)", style)
                dash = re.search(r"stroke-dasharray: ?([^;]+)", style)
                styles.append(f"{stroke.group(1) if stroke else ''}|"
                              f"{dash.group(1) if dash else ''}")
    return styles


def test_each_repeat_has_its_own_line_in_the_utility_plot(tmp_path: Path) -> None:
    write_campaign(tmp_path / "c")
    data = load_campaign(tmp_path / "c")
    svg = utility_over_time(data)
    assert svg is not None
    lines_with_events = 11  # 4 missions x 3 repeats, one crashed run without events.csv
    # every run's line differs from every other (plus the zero line and legend samples)
    assert len(set(_line_styles(svg))) >= lines_with_events + 1


def test_the_repeats_column_is_never_empty(tmp_path: Path) -> None:
    write_campaign(tmp_path / "c")
    _, _, records = CampaignStore.read(tmp_path / "c")
    table = success_table(mission_success(records), "Mission")
    repeats = {row[0]: row[-1] for row in table.rows}
    assert repeats == {"medium_sparse": "none passed", "navigation": "flaky",
                       "small_dense": "flaky", "simple_wall": "all passed"}


def test_the_engine_provenance_reads_as_words() -> None:
    assert _setting({"engine": "local", "workers": 2}) == "local (workers 2)"
    assert _setting({"engine": "dask", "scheduler": "tcp://127.0.0.1:8786"}) == \
        "dask (scheduler tcp://127.0.0.1:8786)"
    assert _setting(["a", 1.5]) == "a, 1.5"


def test_a_mission_passing_every_run_says_why_its_interval_is_wide() -> None:
    verdict = judge_mission(SuccessRate("m", 3, 3, 1.0, 0.44, 1.0), 0.9)
    assert verdict.verdict == "pass"
    assert "straddles" not in verdict.reason
    assert "every run passed (the interval is wide only because the runs are few)" in \
        verdict.reason
