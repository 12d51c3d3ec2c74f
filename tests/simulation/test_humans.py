"""Reactive humans and seeded variations, in the real simulator with a robot that stands still.

A human walks a straight corridor through the robot's start: a scripted one walks into it,
a yielding one stops short of it, a social one walks around it. The robot's controller never
moves, so every contact is the human's doing.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from rei.lang.room.model import WALKING_SPEEDS
from rei.runtime.artifacts.monitor_config import load_monitor_config
from rei.runtime.artifacts.world import load_manifest
from rei.runtime.messages.sink import SampleList
from rei.runtime.simulation.animator import HumanVariation, draw_variations
from rei.runtime.simulation.animator.agent import Agent
from rei.runtime.simulation.animator.social_force import (
    SocialForce,
    elliptical_distance,
    social_acceleration,
)
from rei.runtime.simulation.animator.variation import mean_speed
from rei.runtime.simulation.animator.yielding import YieldRule, yield_factor
from rei.runtime.simulation.assembly import LoopRecord, RunConfig, generate_world, run_mission
from tests.robot.faulty import Idle

ROOM = """room corridor {
    grid g {
        "###########"
        "#.........#"
        "#.........#"
        "#.........#"
        "###########"
    }
    robot r : turtlebot3_waffle on g_2_5
    human walker on g_2_1 trajectory stop { g_2_1 at 0  g_2_9 at 8 }BEHAVIOUR
}
"""
MISSION = """mission stand in "corridor.room" {
    goal here at g_2_5 tolerance 0.3 timeout 30
    goal there at g_2_6 tolerance 0.3 timeout 30
}
"""


def _run(folder: Path, behaviour: str | None, seed: int = 0, vary: bool = False,
         duration: float = 14.0) -> tuple[LoopRecord, np.ndarray]:
    """The run's record and the walker's (x, y) at every sample."""
    folder.mkdir(parents=True, exist_ok=True)
    text = ROOM.replace("BEHAVIOUR", f" behaviour {behaviour}" if behaviour else "")
    (folder / "corridor.room").write_text(text, encoding="utf-8")
    (folder / "stand.mission").write_text(MISSION, encoding="utf-8")
    mission = generate_world(folder / "stand.mission", folder / "world")
    manifest = load_manifest(folder / "world")
    samples = SampleList()
    record = run_mission(mission, manifest, load_monitor_config(folder / "world"), Idle(),
                         [samples], RunConfig(seed=seed, duration=duration, watchdog=None,
                                              vary=vary))
    walker = len(manifest.walls) + [b.name for b in manifest.objects].index("walker")
    return record, np.array([s.poses[walker, :2] for s in samples.samples])


def test_a_scripted_human_walks_into_a_robot_standing_in_its_way(tmp_path: Path) -> None:
    record, path = _run(tmp_path, None)
    # It shoves the robot ahead of it to the corridor's end wall (x = 4.5): an upright
    # 75 kg person does not tip over the robot and slide past it (issue 25).
    assert record.measurements["collided_with"] == ["g_2_10", "walker"]
    assert path[-1, 0] == pytest.approx(4.5 - 0.25 - 0.281, abs=0.02)
    assert record.measurements["variations"]["walker"]["behaviour"] == "scripted"


def test_a_yielding_human_stops_short_of_the_robot_and_never_touches_it(tmp_path: Path) -> None:
    record, path = _run(tmp_path, "yielding", duration=24.0)
    assert record.measurements["collisions"] == 0
    # It walked up to the robot (at the origin) and stood short of it
    waiting = path[42:62]
    assert np.all(waiting[:, 0] < -0.5) and np.ptp(waiting[:, 0]) < 0.05
    # having waited its patience out it stepped aside, across the robot's heading, stood
    # aside a while and then walked on past the robot, never through it
    assert np.abs(path[:, 1]).max() > 1.0
    beside = np.abs(path[:, 0]) < 0.45
    assert beside.any() and np.all(np.abs(path[beside, 1]) > 0.45)
    assert path[-1, 0] > 3.5


def test_a_social_human_walks_around_a_standing_robot(tmp_path: Path) -> None:
    record, path = _run(tmp_path, "social", duration=16.0)
    assert record.measurements["collisions"] == 0
    assert path[-1, 0] > 3.0  # it got past the robot
    assert np.max(np.abs(path[:, 1])) > 0.4  # by stepping aside


def test_the_same_seed_walks_the_same_humans_bit_for_bit(tmp_path: Path) -> None:
    a_rec, a = _run(tmp_path / "a", "social", seed=3, vary=True, duration=6.0)
    b_rec, b = _run(tmp_path / "b", "social", seed=3, vary=True, duration=6.0)
    c_rec, c = _run(tmp_path / "c", "social", seed=4, vary=True, duration=6.0)
    assert a.tobytes() == b.tobytes()
    assert a_rec.measurements["variations"] == b_rec.measurements["variations"]
    assert a.tobytes() != c.tobytes()
    assert a_rec.measurements["variations"] != c_rec.measurements["variations"]


def test_variations_are_seeded_in_range_and_keep_walking_speeds(tmp_path: Path) -> None:
    from rei.runtime.simulation.animator import CatmullRom  # noqa: PLC0415

    slow = CatmullRom(np.array([0.0, 10.0]), np.array([[0.0, 0.0], [5.0, 0.0]]), False)
    fast = CatmullRom(np.array([0.0, 4.0, 8.0]), np.array([[0.0, 0.0], [5.5, 0.0], [11, 0]]),
                      False)
    assert draw_variations(7, [slow, fast]) == draw_variations(7, [slow, fast])
    assert draw_variations(7, [slow]) != draw_variations(8, [slow])
    # Adding a human never changes what an earlier one drew.
    assert draw_variations(7, [slow, fast])[0] == draw_variations(7, [slow])[0]
    for seed in range(50):
        s, f = draw_variations(seed, [slow, fast])
        assert 0.0 <= s.phase_s < 10.0 and 0.0 <= f.phase_s < 4.0
        assert 0.85 - 1e-12 <= s.speed_scale <= 1.15 + 1e-12
        assert WALKING_SPEEDS[0] - 1e-9 <= mean_speed(slow) * s.speed_scale
        assert mean_speed(fast) * f.speed_scale <= WALKING_SPEEDS[1] + 1e-9
    assert HumanVariation() == HumanVariation(0.0, 1.0)


@pytest.mark.parametrize(("robot", "expected"), [
    ((3.0, 0.0), 1.0),    # far ahead
    ((0.9, 0.0), 0.0),    # just ahead: stand
    ((-0.9, 0.0), 1.0),   # behind
    ((0.9, 1.5), 1.0),    # beside, out of the cone
])
def test_the_yield_rule_looks_ahead_in_a_cone(robot: tuple[float, float],
                                              expected: float) -> None:
    factor = yield_factor(YieldRule(), 0.0, 0.0, 0.25, (1.0, 0.0), Agent(*robot, 0.2))
    assert math.isclose(factor, expected)


def test_a_robot_coming_closer_repels_a_social_human_more_than_one_driving_away() -> None:
    model = SocialForce()
    towards = Agent(2.0, 0.0, 0.2, -0.26, 0.0)
    away = Agent(2.0, 0.0, 0.2, 0.26, 0.0)
    standing = Agent(2.0, 0.0, 0.2)
    push = [social_acceleration(model, 0.0, 0.0, 1.0, 0.0, 0.25, (1.0, 0.0), [a])[0]
            for a in (towards, standing, away)]
    assert push[0] < push[1] < push[2] < 0.0  # all push back; the oncoming robot most
    assert elliptical_distance(2.0, 0.0, 0.0, 0.0) == 2.0


SCENES = Path(__file__).parents[1] / "scenes"


def _reference_run(folder: Path, room_text: str) -> LoopRecord:
    from rei.runtime.robot.selection import make_controller  # noqa: PLC0415

    folder.mkdir(parents=True, exist_ok=True)
    (folder / "crossing.room").write_text(room_text, encoding="utf-8")
    (folder / "crossing.mission").write_text((SCENES / "crossing.mission").read_text("utf-8"),
                                             encoding="utf-8")
    mission = generate_world(folder / "crossing.mission", folder / "world")
    return run_mission(mission, load_manifest(folder / "world"),
                       load_monitor_config(folder / "world"), make_controller("reference"), [],
                       RunConfig(seed=0, watchdog=None))


def test_reactive_humans_make_the_test_fair_to_a_correct_navigator(tmp_path: Path) -> None:
    """The crossing scene: a yielding and a social human in the robot's way. The reference
    navigator passes it; with the same humans scripted it is walked into."""
    room = (SCENES / "crossing.room").read_text("utf-8")
    reactive = _reference_run(tmp_path / "reactive", room)
    assert reactive.outcome == "completed" and reactive.measurements["collisions"] == 0
    scripted = _reference_run(tmp_path / "scripted",
                              room.replace(" behaviour yielding", "")
                              .replace(" behaviour social", ""))
    assert scripted.measurements["collisions"] > 0
