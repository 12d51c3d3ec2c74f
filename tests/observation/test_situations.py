"""Situation coverage (rei.runtime.observation.model.situations): what the world put the robot
in, read from the ground truth of synthetic streams through the monitor's own model."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from rei.catalogue import Cylinder
from rei.runtime.messages import GoalFacts, MissionEvent, MissionFacts, ObservedObject, Sample
from rei.runtime.observation.model.runtime_model import RuntimeModel
from rei.runtime.observation.model.situations import SITUATIONS, STANDING_FOR, SituationLog
from tests.observation.streams import drive, human, straight, wall

DT = 0.1


def situations(header: object, samples: list[Sample]) -> dict[str, dict[str, float]]:
    model = RuntimeModel(header)  # type: ignore[arg-type]
    for s in samples:
        model.observe(s)
        for e in s.events:
            model.apply(e, model.baseline())
    return model.situations.to_json()  # type: ignore[return-value]


def moving(samples: list[Sample], speed: float = 0.2) -> list[Sample]:
    return [replace(s, robot_twist=(speed, 0.0, 0.0)) for s in samples]


def test_a_person_walking_across_ahead_is_crossing_and_one_walking_along_is_not() -> None:
    header, samples = drive([human("p", 1.5, -1.0)], straight(0.0, 0.5, 11))
    across = [replace(s, poses=np.array([[1.5, -1.0 + 0.06 * k, 0.0]]),
                      twists=np.array([[0.0, 0.6, 0.0]])) for k, s in enumerate(samples)]
    found = situations(header, moving(across))
    assert found["person_crossing_ahead"]["episodes"] == 1
    along = [replace(s, poses=np.array([[1.5 + 0.06 * k, 0.3, 0.0]]),
                     twists=np.array([[0.6, 0.0, 0.0]])) for k, s in enumerate(samples)]
    assert "person_crossing_ahead" not in situations(header, moving(along))


def test_a_person_standing_on_the_way_counts_only_after_standing_for_long() -> None:
    steps = round(STANDING_FOR / DT)
    header, samples = drive([human("p", 0.9, 0.0)], [(0.0, 0.0, 0.0)] * (steps + 6))
    found = situations(header, samples)
    assert found["person_standing_on_route"]["first"] == round(steps * DT, 3)
    header, short = drive([human("p", 0.9, 0.0)], [(0.0, 0.0, 0.0)] * (steps - 5))
    assert "person_standing_on_route" not in situations(header, short)
    # behind the robot is not on its way
    header, behind = drive([human("p", -0.9, 0.0)], [(0.0, 0.0, 0.0)] * (steps + 6))
    assert "person_standing_on_route" not in situations(header, behind)


def test_a_passage_narrower_than_twice_the_robot_is_narrow_a_wide_one_is_not() -> None:
    # walls 1 m tiles beside the robot's way; the robot is 0.306 m wide
    def passage(gap: float) -> dict[str, dict[str, float]]:
        y = 0.5 + gap / 2
        placed = [wall(f"l{k}", float(k), y) for k in range(4)] + \
            [wall(f"r{k}", float(k), -y) for k in range(4)]
        header, samples = drive(placed, straight(0.5, 2.5, 21))
        return situations(header, moving(samples))

    assert "narrow_passage" in passage(0.5)  # 0.5 m: 0.19 m spare, less than the width
    assert "narrow_passage" not in passage(1.0)
    header, samples = drive([wall("l", 1.0, 0.75), wall("r", 1.0, -0.75)], straight(0, 2, 21))
    assert "narrow_passage" not in situations(header, samples)  # standing still: not passing


def test_a_goal_behind_the_robot_when_its_task_starts() -> None:
    goals = (GoalFacts("front", 3.0, 0.0, None, 0.3, 0.26, 60.0),
             GoalFacts("back", -3.0, 0.0, None, 0.3, 0.26, 60.0))
    facts = MissionFacts(goals, 1, 300.0, 0.26, 1.82, None)
    for goal, expected in (("front", False), ("back", True)):
        header, samples = drive([], [(0.0, 0.0, 0.0)] * 3,
                                events={1: (MissionEvent("task_start", 0.1, goal, 0),)})
        header = replace(header, mission_facts=facts)
        assert ("goal_behind" in situations(header, samples)) == expected, goal


def test_a_cart_beside_the_robot_is_an_obstacle_the_map_does_not_show() -> None:
    cart = ObservedObject("cart", "dynamic", "cart", Cylinder(0.3), 0.8)
    header, samples = drive([(cart, (0.0, 1.0, 0.0))], straight(0.0, 0.2, 3))
    assert "unmapped_obstacle" in situations(header, samples)
    header, samples = drive([(cart, (0.0, 3.0, 0.0))], straight(0.0, 0.2, 3))
    assert "unmapped_obstacle" not in situations(header, samples)


def test_every_situation_has_a_meaning_and_the_log_is_deterministic() -> None:
    assert all(SITUATIONS.values())
    header, samples = drive([human("p", 0.9, 0.0)], [(0.0, 0.0, 0.0)] * 80)
    assert situations(header, samples) == situations(header, samples)
    assert math.isfinite(situations(header, samples)["person_standing_on_route"]["seconds"])


def test_a_hazard_first_seen_close_appears_one_seen_walking_up_does_not() -> None:
    header, samples = drive([], [(0.0, 0.0, 0.0)] * 4)
    appears = SituationLog(header)
    for s, seen in zip(samples, (1e3, 1e3, 1.6, 1.2), strict=True):  # nothing, then 1.6 m
        appears.observe(s, np.zeros(0), seen)
    assert appears.to_json()["hazard_appears_close"]["first"] == samples[2].time
    walks_up = SituationLog(header)
    for s, seen in zip(samples, (1e3, 2.9, 2.2, 1.6), strict=True):  # seen from 2.9 m on
        walks_up.observe(s, np.zeros(0), seen)
    assert "hazard_appears_close" not in walks_up.to_json()
