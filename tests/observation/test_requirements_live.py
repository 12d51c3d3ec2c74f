"""Each requirement a navigation stack owes, shown on real pybullet runs: the correct reference
navigator passes it, a navigator with the matching defect (bench/defects) fails it, and the
failure names that requirement (a test of the test). Synthetic-stream versions of the same
checks are in tests/observation/test_default_requirements.py."""

from __future__ import annotations

from pathlib import Path

import pytest

from rei.runtime.results import RunSummary
from rei.runtime.runs.session import run_into
from tests.conftest import EXAMPLES

SIMPLE_WALL = EXAMPLES / "simple_wall" / "simple_wall.mission"
CROSSING = Path(__file__).parents[1] / "scenes" / "crossing.mission"
GHOST_TRAIL = Path(__file__).parents[1] / "scenes" / "ghost_trail.mission"
NAVIGATION = EXAMPLES / "navigation" / "navigation.mission"


def _verdicts(summary: RunSummary) -> dict[str, str]:
    return {v.requirement: v.status for v in summary.verdicts}


def _slow_mission(folder: Path) -> Path:
    """simple_wall's mission with a mission speed limit under the drive's 0.26 m/s."""
    folder.mkdir(parents=True, exist_ok=True)
    room = (EXAMPLES / "simple_wall" / "simple_wall.room").read_text(encoding="utf-8")
    (folder / "simple_wall.room").write_text(room, encoding="utf-8")
    text = SIMPLE_WALL.read_text(encoding="utf-8").replace(
        'in "simple_wall.room" {', 'in "simple_wall.room" {\n    max_speed 0.15')
    assert "max_speed 0.15" in text
    (folder / "slow.mission").write_text(text, encoding="utf-8")
    return folder / "slow.mission"


@pytest.mark.parametrize(("mission", "defect", "requirement"), [
    ("simple_wall", "control:ExceedsDriveLimit", "SPEED_LIMIT"),
    ("slow", "control:IgnoresMissionSpeed", "SPEED_LIMIT"),
    # the elevator goal faces east, across the way the robot arrives
    ("navigation", "mission:IgnoresGoalHeading", "GOAL_HEADING"),
    ("crossing", "control:NoSlowZone", "HUMAN_SLOW_ZONE"),
    ("simple_wall", "teleop", "NO_ROBOT_COLLISION"),
    ("small_dense", "control:OscillatingHeading", "SMOOTH_MOTION"),
    # the walker's trail shuts the gap between two shelves: path ratio 1.6 against 1.02
    ("ghost_trail", "planning:NeverClearsObstacles", "EFFICIENT_PATH"),
    # crawling at 0.05 m/s while the elevator is far: time ratio 8.6 against 1.15
    ("navigation", "control:InvertedApproachScaling", "TIME_TO_GOAL"),
    # a full turn (twice) on top of the quarter turn to the elevator's heading: 7.5 rad
    ("navigation", "control:SpinsWhenTurning", "NO_SPIN_AT_GOAL"),
])
def test_the_reference_passes_and_the_defect_fails(tmp_path: Path, mission: str, defect: str,
                                                   requirement: str) -> None:
    path = {"simple_wall": SIMPLE_WALL, "crossing": CROSSING, "navigation": NAVIGATION,
            "small_dense": EXAMPLES / "small_dense" / "small_dense.mission",
            "ghost_trail": GHOST_TRAIL}.get(mission) or \
        _slow_mission(tmp_path / "mission")
    good, _ = run_into(path, tmp_path / "reference")
    assert good.verdict == "pass", [v for v in good.verdicts if v.status != "pass"]
    assert _verdicts(good)[requirement] == "pass"
    controller = defect if ":" not in defect else f"bench.defects.{defect}"
    bad, _ = run_into(path, tmp_path / "defect", controller)
    assert bad.verdict == "fail"
    verdict = next(v for v in bad.verdicts if v.requirement == requirement)
    assert verdict.status == "fail", bad.verdicts
    assert verdict.decided_at is not None and verdict.reason


def test_a_defect_that_remembers_what_it_saw_is_still_deterministic(tmp_path: Path) -> None:
    """NeverClearsObstacles keeps a growing set of remembered points and re-plans from it:
    the same scenario and seed still give byte-identical traces and event logs."""
    controller = "bench.defects.planning:NeverClearsObstacles"
    run_into(GHOST_TRAIL, tmp_path / "a", controller)
    run_into(GHOST_TRAIL, tmp_path / "b", controller)
    for name in ("trace.jsonl", "events.csv", "summary.json"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
