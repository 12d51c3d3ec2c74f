"""Margins on real pybullet runs (the robot under test in its own process): the sign agrees
with the verdict on a pass and on a fail of several requirements, summary.json carries them,
and the same scenario and seed give byte-identical summaries."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from rei.runtime.results import RunSummary
from rei.runtime.runs.session import run_into
from tests.conftest import EXAMPLES

REPO = Path(__file__).resolve().parents[2]
MISSION = EXAMPLES / "simple_wall" / "simple_wall.mission"


def _run(out: Path, controller: str) -> RunSummary:
    summary, _ = run_into(MISSION, out, controller=controller, seed=3)
    return summary


def _check_signs(summary: RunSummary) -> dict[str, float]:
    margins = {}
    for v in summary.verdicts:
        if v.margin is not None:
            assert (v.margin < 0) == (v.status == "fail"), v
            margins[v.requirement] = v.margin
        elif v.status in ("inconclusive", "not_applicable"):
            assert v.margin is None
    return margins


@pytest.mark.slow
def test_real_runs_margins_agree_with_verdicts(tmp_path: Path,
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(
        p for p in (str(REPO), os.environ.get("PYTHONPATH", "")) if p))
    good = _run(tmp_path / "reference", "reference")
    assert good.verdict == "pass"
    ok = _check_signs(good)
    for name in ("SPEED_LIMIT", "NO_ROBOT_COLLISION", "MISSION_GOALS_REACHED", "SETTLE"):
        assert ok[name] >= 0, name
    fast = _run(tmp_path / "fast", "bench.defects.control:ExceedsDriveLimit")
    bad = _check_signs(fast)
    assert {v.requirement: v.status for v in fast.verdicts}["SPEED_LIMIT"] == "fail"
    assert bad["SPEED_LIMIT"] < 0 <= ok["SPEED_LIMIT"]
    crash = _run(tmp_path / "teleop", "teleop")  # drives straight into the east wall
    hit = _check_signs(crash)
    assert hit["NO_ROBOT_COLLISION"] < 0 <= ok["NO_ROBOT_COLLISION"]
    # teleop never reaches the goal at the wall: a failed goal, no time left
    assert hit["MISSION_GOALS_REACHED"] == -1.0 < 0 < ok["MISSION_GOALS_REACHED"] <= 1
    # summary.json carries them, and a second run of the same scenario and seed is identical
    again = _run(tmp_path / "again", "reference")
    assert again == good
    text = (tmp_path / "reference" / "summary.json").read_bytes()
    assert b'"margin"' in text and b'"margin_unit"' in text
    assert (tmp_path / "again" / "summary.json").read_bytes() == text
