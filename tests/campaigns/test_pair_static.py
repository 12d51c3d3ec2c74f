"""--pair-static: every run next to its twin in the same room without people, and a real small
campaign telling "fails with people only" from "fails in the static room too"."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from rei.lang.workspace import load_mission
from rei.runtime.campaigns import (
    CampaignError,
    CampaignPlan,
    CampaignStore,
    classify_pairs,
    mission_verdicts,
    plan_campaign,
    static_twin,
)

from .conftest import require_rei_run
from .records import EXAMPLES

SAFETY_LIMIT = 600.0
"""Seconds after which a stuck test fails instead of hanging CI (not a performance limit)."""

CORRIDOR = """\
// A one-tile corridor; a person stands in its middle, another in a side pocket.
room corridor {
    grid hall {
        legend {
            "S" = floor start
            "G" = floor goal
        }
        "######"
        "#S..G#"
        "##.###"
        "######"
    }

    robot bot : turtlebot3_waffle on start heading 0
    human blocker on hall_1_3 heading 90
    dynamic trolley : cart on hall_2_2
}
"""

POCKET = CORRIDOR.replace("human blocker on hall_1_3 heading 90\n", "")

MISSION = """\
mission {name} in "{room}" {{
    goal begin at start tolerance 0.3 timeout 5
    goal end at goal tolerance 0.3 timeout {timeout}
}}
"""


def write_missions(folder: Path) -> Path:
    """blocked: the person blocks the corridor (fails with people only); hurried: a timeout
    nobody meets (fails in the static room too); clear: nobody in the way (passes)."""
    (folder / "rooms").mkdir(parents=True)
    (folder / "rooms" / "corridor.room").write_text(CORRIDOR)
    (folder / "rooms" / "pocket.room").write_text(POCKET)
    for name, room, timeout in (("blocked", "rooms/corridor.room", 25),
                                ("hurried", "rooms/corridor.room", 1),
                                ("clear", "rooms/pocket.room", 25)):
        (folder / f"{name}.mission").write_text(MISSION.format(name=name, room=room,
                                                               timeout=timeout))
    return folder


def test_the_twin_is_the_room_without_humans_and_dynamic_objects(tmp_path: Path) -> None:
    write_missions(tmp_path)
    twin = static_twin(tmp_path / "blocked.mission")
    assert twin.removed == ("blocker", "trolley")
    assert twin.room_name == "corridor.room"
    assert 'in "corridor.room"' in twin.mission_text  # the twin room sits next to the mission
    assert twin.mission_text.replace('"corridor.room"', '"rooms/corridor.room"') == \
        (tmp_path / "blocked.mission").read_text()
    # Everything else is the original text: grids, comments, the robot and static objects.
    kept = [line for line in CORRIDOR.splitlines()
            if "blocker" not in line and "trolley" not in line]
    assert [line for line in twin.room_text.splitlines()[2:] if line.strip()] == \
        [line for line in kept if line.strip()]
    (tmp_path / "twin").mkdir()
    (tmp_path / "twin" / twin.room_name).write_text(twin.room_text)
    (tmp_path / "twin" / "blocked.mission").write_text(twin.mission_text)
    doc = load_mission(tmp_path / "twin" / "blocked.mission")  # a valid mission and room
    assert doc.room is not None and doc.room.room is not None
    assert {o.role for o in doc.room.room.objects} == {"robot"}
    # Twice removed is once removed.
    assert static_twin(tmp_path / "twin" / "blocked.mission").removed == ()


def test_a_catalogue_path_still_names_the_same_file_from_the_twin(tmp_path: Path) -> None:
    write_missions(tmp_path)
    catalogue = Path(__file__).resolve().parents[2] / "catalogue" / "default.toml"
    room = tmp_path / "rooms" / "corridor.room"
    (tmp_path / "rooms" / "default.toml").write_bytes(catalogue.read_bytes())
    room.write_text(CORRIDOR.replace("    grid hall",
                                     '    catalogue "default.toml"\n    grid hall'))
    twin = static_twin(tmp_path / "blocked.mission")
    expected = (tmp_path / "rooms" / "default.toml").resolve().as_posix()
    assert f'catalogue "{expected}"' in twin.room_text


def test_a_mission_that_does_not_load_is_named(tmp_path: Path) -> None:
    (tmp_path / "bad.mission").write_text('mission bad in "nowhere.room" {\n}\n')
    with pytest.raises(CampaignError, match=r"bad\.mission: cannot make its static twin"):
        static_twin(tmp_path / "bad.mission")


def test_paired_plan_interleaves_twins_with_the_same_seed_and_stable_ids(tmp_path: Path) -> None:
    plain = plan_campaign([EXAMPLES / "navigation"], repeat=2, seed=3)
    paired = plan_campaign([EXAMPLES / "navigation"], repeat=2, seed=3,
                           static_dir=tmp_path / "static")
    assert [r.run_id for r in paired.runs] == ["navigation.r00", "navigation.static.r00",
                                               "navigation.r01", "navigation.static.r01"]
    people, twin = paired.runs[:2]
    assert people.seed == twin.seed == plain.runs[0].seed
    assert (people.static_pair, twin.static_pair) == (False, True)
    assert people.pair == twin.pair == "navigation.r00"
    assert people.mission_file == plain.runs[0].mission_file
    assert twin.mission_file == str((tmp_path / "static" / "navigation" /
                                     "navigation.mission").resolve())
    assert twin.run_argv("out")[1] == twin.mission_file
    # Stable across sessions (resume compares plans), and through campaign.json.
    assert paired == plan_campaign([EXAMPLES / "navigation"], repeat=2, seed=3,
                                   static_dir=tmp_path / "static")
    assert CampaignPlan.from_json(paired.to_json()) == paired
    # An unpaired plan is written as before --pair-static existed.
    assert "pair" not in plain.runs[0].to_json()


def _campaign(out: Path, missions: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "rei.runtime.commands", "campaign", str(missions),
                           "-o", str(out), "--repeat", "2", "--workers", "2", "--no-report",
                           "--pair-static", *extra],
                          capture_output=True, text=True, timeout=SAFETY_LIMIT)


@pytest.mark.slow
def test_a_paired_campaign_tells_the_people_from_the_room(tmp_path: Path) -> None:
    require_rei_run()
    missions = write_missions(tmp_path / "missions")
    out = tmp_path / "campaign"
    done = _campaign(out, missions)
    assert done.returncode == 1, done.stderr  # blocked and hurried fail
    _, _, records = CampaignStore.read(out)
    assert len(records) == 12
    causes = {p.mission: p.cause for p in classify_pairs(records)}
    assert causes == {"blocked": "fails with people only",
                      "clear": "passes",
                      "hurried": "fails in the static room too"}, done.stderr
    verdicts = {v.mission: v.verdict for v in mission_verdicts(records)}
    assert verdicts == {"blocked": "fail", "clear": "pass", "hurried": "fail"}
    assert "FAIL   blocked:" in done.stderr and "fails with people only" in done.stderr
    # Twins ran the twin room, with the same seed (and so the same start pose) as their pair.
    by_id = {r.spec.run_id: r for r in records}
    for record in records:
        if record.spec.static_pair:
            pair = by_id[record.spec.pair]
            assert record.spec.seed == pair.spec.seed
            assert record.summary is not None and pair.summary is not None
            jitter = record.summary.measurements["variations"]["start_jitter"]
            assert jitter == pair.summary.measurements["variations"]["start_jitter"]
    assert (out / "static" / "blocked" / "corridor.room").is_file()
    table = pq.read_table(out / "results.parquet").to_pylist()
    assert {(r["run_id"], r["pair"], r["static_pair"]) for r in table
            if r["run_id"].startswith("clear")} == {
        ("clear.r00", "clear.r00", False), ("clear.static.r00", "clear.r00", True),
        ("clear.r01", "clear.r01", False), ("clear.static.r01", "clear.r01", True)}
    # The same command again: every run is already there (ids stable across sessions), and
    # a lower required rate judges the same runs anew without running anything.
    again = _campaign(out, missions, "--pass-rate", "0")
    assert "12 of 12 runs already recorded" in again.stderr
    assert again.returncode == 0, again.stderr
