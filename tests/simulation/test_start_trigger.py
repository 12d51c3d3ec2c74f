"""A trajectory's start trigger in the real simulator: the mover stands on its first vertex
until the robot comes within the trigger's distance of the floor, then walks its timed path.

A robot drives straight down a corridor at a fixed speed (tests.robot.scripted.Ram); a
person waits in an alcove beside the corridor, its trajectory started by the robot coming
within 1.5 m of the alcove's mouth. At two robot speeds the person must start at the same
robot position (the trigger is a place, not a time), and a trajectory without a trigger
(the same room with it removed) must not.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from rei.runtime.artifacts.monitor_config import load_monitor_config
from rei.runtime.artifacts.world import load_manifest
from rei.runtime.messages.sink import SampleList
from rei.runtime.simulation.assembly import LoopRecord, RunConfig, generate_world, run_mission
from tests.robot.scripted import Ram

ROOM = """room hall {
    grid g {
        "###########"
        "#####.#####"
        "#.........#"
        "###########"
    }
    robot r : turtlebot3_waffle on g_2_1
    human stepper on g_1_5 trajectory stop TRIGGER { g_1_5 at 0  g_2_5 at 1.5 } behaviour scripted
}
"""
MISSION = """mission pass in "hall.room" {
    goal here at g_2_1 tolerance 0.3 timeout 60
    goal far at g_2_9 tolerance 0.3 timeout 60
}
"""
WITHIN = 1.5
MOUTH = (4.0, 0.0)
"""The trigger floor g_2_5's centre (the test checks it against the generated world)."""


def _run(folder: Path, speed: float, trigger: bool = True, duration: float = 24.0
         ) -> tuple[LoopRecord, np.ndarray, np.ndarray, np.ndarray]:
    """The record, the sample times, the robot's (x, y) and the stepper's (x, y)."""
    folder.mkdir(parents=True, exist_ok=True)
    clause = f"when robot within {WITHIN} of g_2_5" if trigger else ""
    (folder / "hall.room").write_text(ROOM.replace("TRIGGER", clause), encoding="utf-8")
    (folder / "pass.mission").write_text(MISSION, encoding="utf-8")
    mission = generate_world(folder / "pass.mission", folder / "world")
    manifest = load_manifest(folder / "world")
    assert ("g_2_5", *MOUTH) in manifest.floors
    samples = SampleList()
    record = run_mission(mission, manifest, load_monitor_config(folder / "world"), Ram(speed),
                         [samples], RunConfig(seed=0, duration=duration, watchdog=None))
    k = len(manifest.walls) + [b.name for b in manifest.objects].index("stepper")
    times = np.array([s.time for s in samples.samples])
    robot = np.array([s.robot_pose[:2] for s in samples.samples])
    stepper = np.array([s.poses[k, :2] for s in samples.samples])
    return record, times, robot, stepper


def _first_move(stepper: np.ndarray) -> int:
    """The first sample at which the stepper has left its first vertex by 2 cm."""
    moved = np.hypot(*(stepper - stepper[0]).T) > 0.02
    assert moved.any(), "the stepper never moved"
    return int(np.argmax(moved))


def _robot_distance(robot: np.ndarray, at: int) -> float:
    return math.dist(robot[at], MOUTH)


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[LoopRecord, np.ndarray,
                                                                      np.ndarray, np.ndarray]]:
    base = tmp_path_factory.mktemp("trigger")
    return {"slow": _run(base / "slow", 0.15), "fast": _run(base / "fast", 0.26),
            "untriggered": _run(base / "untriggered", 0.15, trigger=False)}


def test_the_mover_stands_until_the_robot_comes_within_the_distance(runs) -> None:  # type: ignore[no-untyped-def]
    for key in ("slow", "fast"):
        record, times, robot, stepper = runs[key]
        at = _first_move(stepper)
        # It stood on its first vertex the whole time before (a standing body, not a slow one)
        assert np.ptp(stepper[:at], axis=0).max() < 0.02
        # and started when the robot was at the trigger distance (one control tick and
        # the 2 cm threshold: at most a few centimetres of the robot's way)
        assert WITHIN - 0.1 < _robot_distance(robot, at) <= WITHIN + 0.01, key
        started = record.measurements["variations"]["stepper"]["started_s"]
        assert started is not None and abs(started - times[at]) < 0.5


def test_two_robot_speeds_meet_the_mover_at_the_same_distance(runs) -> None:  # type: ignore[no-untyped-def]
    slow, fast = runs["slow"], runs["fast"]
    d_slow = _robot_distance(slow[2], _first_move(slow[3]))
    d_fast = _robot_distance(fast[2], _first_move(fast[3]))
    assert abs(d_slow - d_fast) < 0.08
    # at different times: the clock is the robot's position, not the run's
    assert fast[1][_first_move(fast[3])] < slow[1][_first_move(slow[3])] - 2.0
    # and after starting, it walks its timed path: out of the alcove in 1.5 s, onto g_2_5
    for _, times, _, stepper in (slow, fast):
        at = _first_move(stepper)
        later = int(np.searchsorted(times, times[at] + 2.0))
        assert math.dist(stepper[later], MOUTH) < 0.15


def test_without_a_trigger_the_mover_starts_with_the_run(runs) -> None:  # type: ignore[no-untyped-def]
    record, _, robot, stepper = runs["untriggered"]
    at = _first_move(stepper)
    # the test's own control: the same room untriggered starts far before the robot is near
    assert _robot_distance(robot, at) > WITHIN + 1.0
    assert "started_s" not in record.measurements["variations"]["stepper"]


def test_same_seed_same_stream_with_a_trigger(tmp_path: Path) -> None:
    _, _, robot_a, stepper_a = _run(tmp_path / "a", 0.26, duration=14.0)
    _, _, robot_b, stepper_b = _run(tmp_path / "b", 0.26, duration=14.0)
    assert robot_a.tobytes() == robot_b.tobytes() and stepper_a.tobytes() == stepper_b.tobytes()
