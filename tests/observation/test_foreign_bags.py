"""`rei replay BAG --mission M.mission` on ROS 2 bags REI did not make (issue 24.2, 24.6):
written with rosbags' own Writer (tests/observation/foreign_bags.py), judged with the default
.vepl. A good drive passes (MCAP and sqlite3 storage alike); a stack that claims SUCCEEDED
short of the goal fails; hostile bags (missing topics, unknown frames, stamps going
backwards, NaN poses, gaps, a truncated file, a 10^6-message topic, a scan whose header does
not describe its ranges) are located errors or inconclusive: never a traceback, a hang or a
pass."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest
from rosbags.rosbag2 import StoragePlugin

from rei.runtime.commands.cli import main as rei
from tests.conftest import EXAMPLES
from tests.observation.foreign_bags import Drive, variant, write_bag

MISSION = EXAMPLES / "simple_wall" / "simple_wall.mission"


def _judge(bag: Path, out: Path, capsys: pytest.CaptureFixture[str],
           *extra: str) -> tuple[int, str, dict[str, Any]]:
    capsys.readouterr()
    status = rei(["replay", str(bag), "--mission", str(MISSION), "-o", str(out), *extra])
    captured = capsys.readouterr()
    summary = json.loads((out / "summary.json").read_text()) \
        if (out / "summary.json").is_file() else {}
    return status, captured.err, summary


def _events(out: Path) -> list[tuple[str, str]]:
    rows = (out / "events.csv").read_text().splitlines()[1:]
    return [(r.split(",")[0], r.split(",")[1]) for r in rows]


@pytest.mark.parametrize("storage", [StoragePlugin.MCAP, StoragePlugin.SQLITE3])
def test_a_good_drive_passes_with_the_default_vepl(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], storage: StoragePlugin) -> None:
    bag = write_bag(tmp_path / "bag", variant(storage=storage))
    status, err, summary = _judge(bag, tmp_path / "out", capsys)
    assert status == 0, err
    assert summary["verdict"] == "pass" and summary["outcome"] == "completed"
    # the second goal (x = 2, tolerance 0.25) is reached when x = 1.75, at 0.25 m/s: t = 7 s
    assert ("7.0", "SIG_MISSION_TASK_SUCCESS") in _events(tmp_path / "out")
    # REI's exact trace of the judged stream, for the run page and later replays
    assert (tmp_path / "out" / "trace.jsonl").is_file()
    assert (tmp_path / "out" / "report.html").is_file()


def test_the_mcap_file_itself_is_read_too(tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    bag = write_bag(tmp_path / "bag")
    status, err, _ = _judge(next(bag.glob("*.mcap")), tmp_path / "out", capsys)
    assert status == 0, err


def test_nav2_says_succeeded_and_the_truth_agrees(tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    bag = write_bag(tmp_path / "bag", variant(nav2=True))
    status, err, _ = _judge(bag, tmp_path / "out", capsys)
    assert status == 0, err
    # Nav2's SUCCEEDED (on arrival at x = 1.8, t = 7.2 s) ends the task, not the first pose
    # within tolerance
    assert ("7.2", "SIG_MISSION_TASK_SUCCESS") in _events(tmp_path / "out")


def test_a_success_claimed_short_of_the_goal_fails(tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    """Evidence over claims: Nav2 says SUCCEEDED at t = 3 s, 1.25 m short of the goal."""
    bag = write_bag(tmp_path / "bag", variant(nav2=True, claim_success_at=3.0))
    status, _, summary = _judge(bag, tmp_path / "out", capsys)
    assert status == 1 and summary["verdict"] == "fail"
    failed = {v["requirement"]: v for v in summary["verdicts"] if v["status"] == "fail"}
    assert "MISSION_GOALS_REACHED" in failed
    assert "outside tolerance" in failed["MISSION_GOALS_REACHED"]["reason"]


def test_a_drive_along_the_north_wall_fails(tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    """y = 0.4: the robot (0.306 m wide) overlaps the walls' faces at y = 0.5."""
    bag = write_bag(tmp_path / "bag", variant(y=0.4))
    status, _, summary = _judge(bag, tmp_path / "out", capsys)
    assert status == 1 and summary["verdict"] == "fail"
    assert "NO_ROBOT_COLLISION" in {v["requirement"] for v in summary["verdicts"]
                                    if v["status"] == "fail"}


def test_a_bag_that_ends_before_the_mission_does_not_pass(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bag = write_bag(tmp_path / "bag", variant(duration=4.0))
    status, _, summary = _judge(bag, tmp_path / "out", capsys)
    assert status == 1 and summary["verdict"] != "pass"
    assert summary["outcome"] == "timeout" and "the recording ends at t=4" in summary["reason"]


def test_a_mapping_file_renames_frames_and_topics(tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    bag = write_bag(tmp_path / "bag", variant(parent="world", robot="tb3"))
    status, err, _ = _judge(bag, tmp_path / "out", capsys)
    assert status == 2 and "expected /tf transforms map -> waffle" in err
    mapping = tmp_path / "stack.toml"
    mapping.write_text('[frames]\nmap = "world"\nwaffle = "tb3"\n[topics]\n"/cmd_vel" = '
                       '"/cmd_vel"\n', encoding="utf-8")
    status, err, _ = _judge(bag, tmp_path / "out2", capsys, "--map", str(mapping))
    assert status == 0, err


# ---- hostile bags ---------------------------------------------------------------------------

LOCATED = {
    "missing /odom": (variant(drop=("/odom",)),
                      r"bag: expected the topic /odom \(nav_msgs/msg/Odometry\), found "
                      r"/clock \(rosgraph_msgs/msg/Clock\), /cmd_vel"),
    "missing /tf": (variant(drop=("/tf",)), r"bag: expected the topic /tf "
                                            r"\(tf2_msgs/msg/TFMessage\), found /clock"),
    "unknown frames": (variant(parent="odom", robot="base_link"),
                       r"bag: expected /tf transforms map -> waffle \(the robot's ground "
                       r"truth\), found the frames: odom -> base_link"),
}


@pytest.mark.parametrize("case", list(LOCATED))
def test_a_bag_without_what_rei_needs_is_a_located_error(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], case: str) -> None:
    drive, message = LOCATED[case]
    bag = write_bag(tmp_path / "bag", drive)
    status, err, summary = _judge(bag, tmp_path / "out", capsys)
    assert status == 2 and not summary, err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert re.match(rf"^rei: error: {re.escape(str(tmp_path))}/{message}", err), err


INCONCLUSIVE = {
    "stamps going backwards": (variant(backwards_at=3.0), r"/tf at t=2\.500 s: its stamps go "
                                                          r"backwards"),
    "a NaN pose": (variant(nan_at=3.0), r"/tf at t=3\.000 s: a non-finite pose of waffle"),
    "a gap in the ground truth": (variant(gap=(2.0, 4.0)), r"/tf at t=4\.000 s: a gap of "
                                                           r"2\.100 s"),
    "a scan header that does not describe its ranges": (
        variant(scan_increment=0.0), r"/scan at t=0\.000 s: its header does not describe its "
                                     r"ranges: expected finite angles and a non-zero"),
    "3 ranges for a 360-degree header": (
        variant(scan_ranges=3),
        r"/scan at t=0\.000 s: its header does not describe its ranges"),
}


@pytest.mark.parametrize("case", list(INCONCLUSIVE))
def test_bad_data_makes_the_verdicts_it_touches_inconclusive_never_pass(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], case: str) -> None:
    drive, problem = INCONCLUSIVE[case]
    bag = write_bag(tmp_path / "bag", drive)
    status, err, summary = _judge(bag, tmp_path / "out", capsys)
    assert status == 1, err
    assert summary["verdict"] in ("inconclusive", "fail")
    assert not [v for v in summary["verdicts"] if v["status"] == "pass"]
    problems = summary["measurements"]["recording_problems"]
    assert any(re.match(problem, p) for p in problems), problems


def test_the_good_drive_itself_has_no_problems(tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    """The hostile cases fail for their damage: the same drive without it passes clean."""
    bag = write_bag(tmp_path / "bag", Drive())
    _, _, summary = _judge(bag, tmp_path / "out", capsys)
    assert "recording_problems" not in summary["measurements"]
    assert summary["measurements"]["sample_problems"] == dict.fromkeys(
        summary["measurements"]["sample_problems"], 0)


def test_a_truncated_bag_is_a_located_error(tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    bag = write_bag(tmp_path / "bag")
    mcap = next(bag.glob("*.mcap"))
    data = mcap.read_bytes()
    mcap.write_bytes(data[: len(data) // 2])
    status, err, summary = _judge(bag, tmp_path / "out", capsys)
    assert status in (1, 2) and "Traceback" not in err
    if status == 2:
        assert err.startswith(f"rei: error: {bag}: expected ") and err.count("\n") == 1
    else:
        assert summary["verdict"] != "pass"


def test_not_a_bag_is_a_located_error(tmp_path: Path,
                                      capsys: pytest.CaptureFixture[str]) -> None:
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"not a bag at all")
    status, err, _ = _judge(junk, tmp_path / "out", capsys)
    assert status == 2 and err.startswith(f"rei: error: {junk}: expected a ROS 2 recording")
    status, err, _ = _judge(tmp_path / "nothing", tmp_path / "out", capsys)
    assert status == 2 and "found nothing at that path" in err


def test_a_million_message_topic_rei_does_not_read_is_skipped(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bag = write_bag(tmp_path / "bag", variant(extra={"/chatter": 10**6}))
    status, err, summary = _judge(bag, tmp_path / "out", capsys)
    assert status == 0 and summary["verdict"] == "pass", err


def test_a_bad_mapping_file_is_a_located_error(tmp_path: Path,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    bag = write_bag(tmp_path / "bag")
    mapping = tmp_path / "stack.toml"
    mapping.write_text('[topics]\n"/scna" = "/x"\n', encoding="utf-8")
    status, err, _ = _judge(bag, tmp_path / "out", capsys, "--map", str(mapping))
    assert status == 2
    assert re.match(rf"^rei: error: {re.escape(str(mapping))}: topics\./scna: expected one of "
                    rf"REI's topics .*found '/scna'.*did you mean '/scan'", err), err


def test_ground_truth_faster_than_the_sample_rate_is_sampled_at_it(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A pose bridge at 50 Hz: one sample per 0.1 s (the mission's rate), same judgement."""
    bag = write_bag(tmp_path / "bag", variant(rate=50.0))
    status, err, summary = _judge(bag, tmp_path / "out", capsys)
    assert status == 0, err
    # t = 0.0, 0.1, ..., 10.0 (the end: the last task's success at 7.0, then 3 s settle)
    assert summary["measurements"]["samples"] == 101
    assert ("7.0", "SIG_MISSION_TASK_SUCCESS") in _events(tmp_path / "out")
