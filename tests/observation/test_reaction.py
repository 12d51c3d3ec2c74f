"""REACTION_TIME on synthetic streams (issue 22): the clock starts at the scan that first shows
a person or a moving object ahead within react_zone while the robot commands more than the
slow speed; the robot must command the slow speed within 300 ms. The verdict fails for a
late reaction and passes for a prompt one, its margin (seconds) has the verdict's sign and
falls with the lateness, and what the laser did not see (a person hidden behind a wall, one
behind the robot) or a robot standing still starts nothing. Real pybullet runs:
tests/observation/test_reaction_runs.py."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from rei.catalogue import Box
from rei.runtime.messages import (
    SCHEMA_VERSION,
    LaserScan,
    MissionEvent,
    NavState,
    ObservedObject,
    RobotBelief,
    Sample,
    StreamHeader,
)
from rei.runtime.observation.model.hazard import NONE_SEEN, HazardSensor
from rei.runtime.results import Verdict
from tests.observation.helpers import monitor
from tests.observation.streams import ROBOT, human, wall
from tests.observation.test_default_requirements import RATE, facts

FAST, SLOW = 0.25, 0.1
"""m/s: the robot's cruise command, and the command it slows to (below slow_speed 0.15)."""
HALF = 0.1405
"""m: the synthetic robot's half length (ROBOT's box, 0.281 m): its front edge from the mount."""


def scan(ahead: float, behind: float = 3.5) -> LaserScan:
    """Four beams (behind, right, ahead, left) from the footprint's centre; 3.5 m: no return."""
    return LaserScan(-math.pi, math.pi / 2, 0.12, 3.5, np.array([behind, 3.5, ahead, 3.5]))


def approach(tmp: Path, lag: float | None, placed: list[tuple[ObservedObject, tuple[float, ...]]],
             ahead_of: int | None = 0, behind: bool = False, speed: float = FAST,
             name: str = "run") -> dict[str, Verdict]:
    """The robot drives along +x at ``speed`` towards (or, ``behind``, away from) the object
    ``ahead_of``; a 5 Hz scan's beam ends on that object; the robot commands SLOW ``lag``
    seconds after the first scan that shows it within react_zone, 1.05 m (None: never)."""
    n = 60
    objects = tuple(o for o, _ in placed)
    header = StreamHeader(SCHEMA_VERSION, "synthetic", "synthetic", 0, RATE, ROBOT, objects, 1.0,
                          (), mission_facts=facts())
    poses = np.array([p for _, p in placed], dtype=float).reshape(len(placed), 3)
    x, seen_at = 0.0, None
    samples = []
    for i in range(n):
        t = i / RATE
        this_scan = None
        if i % 2 == 0:
            if ahead_of is None:
                this_scan = scan(3.4)
            else:
                ox = poses[ahead_of, 0]
                gap = abs(ox - x) - 0.25  # from the mount (the centre) to the person's edge
                this_scan = scan(3.5, gap) if behind else scan(gap)
                if seen_at is None and gap - HALF < 1.05:
                    seen_at = t
        slow = lag is not None and seen_at is not None and t >= seen_at + lag - 1e-9
        v = SLOW if slow else speed
        events: tuple[MissionEvent, ...] = ()
        if i == 0:
            events = (MissionEvent("begin", 0.0), MissionEvent("task_start", 0.0, "g0", 0))
        elif i == n - 2:
            events = (MissionEvent("task_success", t, "g0", 0),)
        elif i == n - 1:
            events = (MissionEvent("end", t),)
        direction = -1.0 if behind else 1.0
        belief = RobotBelief((x, 0.0, 0.0), (v, 0.0), 3.5, this_scan, NavState.ACTIVE, None,
                             cmd=(v * direction, 0.0))
        samples.append(Sample(i, t, (x, 0.0, 0.0), (v * direction, 0.0, 0.0), poses,
                              np.zeros_like(poses), belief, events))
        x += direction * v / RATE
    _, result = monitor(header, samples, tmp / name)
    return {v.requirement: v for v in result.verdicts}


PERSON = [human("alice", 2.2, 0.0)]


@pytest.mark.parametrize("lag", [0.1, 0.2])
def test_a_prompt_reaction_passes(tmp_path: Path, lag: float) -> None:
    v = approach(tmp_path, lag, PERSON)["REACTION_TIME"]
    assert v.status == "pass", v.reason
    assert v.margin == pytest.approx(0.3 - lag, abs=1e-6)


def test_slowing_with_the_scan_that_shows_the_hazard_starts_nothing(tmp_path: Path) -> None:
    v = approach(tmp_path, 0.0, PERSON)["REACTION_TIME"]
    assert v.status == "pass" and v.margin is None


@pytest.mark.parametrize("lag", [0.35, 0.4, 0.5, 0.8, None])
def test_a_late_reaction_fails(tmp_path: Path, lag: float | None) -> None:
    v = approach(tmp_path, lag, PERSON)["REACTION_TIME"]
    assert v.status == "fail"
    assert "hazardSensedFast" in v.reason
    assert v.margin is not None and v.margin < 0


def test_the_margin_falls_with_the_lateness(tmp_path: Path) -> None:
    margins = []
    for lag in (0.1, 0.2, 0.4, 0.6, 1.0):
        v = approach(tmp_path, lag, PERSON, name=f"lag{lag}")["REACTION_TIME"]
        assert (v.margin is not None) and ((v.margin < 0) == (v.status == "fail"))
        margins.append(v.margin)
    assert margins == sorted(margins, reverse=True) and len(set(margins)) == len(margins)


def test_a_moving_object_is_a_hazard_and_a_wall_is_not(tmp_path: Path) -> None:
    cart = [(ObservedObject("cart", "dynamic", "cart", Box(0.6, 0.4), 0.9), (2.2, 0.0, 0.0))]
    # the beam ends 5 cm inside the cart's box (its half length is 0.3, not 0.25)
    assert approach(tmp_path, None, cart, name="cart")["REACTION_TIME"].status == "fail"
    # the same approach to a wall never starts the clock (walls are on the map)
    walls = [wall("w", 2.45, 0.0), human("far", 9.0, 5.0)]
    v = approach(tmp_path, None, walls, name="wall")["REACTION_TIME"]
    assert v.status == "pass" and v.margin is None


def test_what_the_laser_does_not_see_starts_nothing(tmp_path: Path) -> None:
    # a person 0.5 m behind a wall: the beam ends on the wall, never on the person
    hidden = [wall("w", 1.95, 0.0), human("hidden", 2.95, 0.0)]
    v = approach(tmp_path, None, hidden, ahead_of=0, name="hidden")["REACTION_TIME"]
    assert v.status == "pass" and v.margin is None
    # a person behind the robot, driving away from them
    v = approach(tmp_path, None, [human("bob", -0.5, 0.0)], behind=True,
                 name="behind")["REACTION_TIME"]
    assert v.status == "pass" and v.margin is None


def test_a_slow_robot_has_nothing_to_react_to(tmp_path: Path) -> None:
    v = approach(tmp_path, None, PERSON, speed=SLOW, name="slow")["REACTION_TIME"]
    assert v.status == "pass" and v.margin is None


def test_no_people_or_moving_objects_is_not_applicable(tmp_path: Path) -> None:
    v = approach(tmp_path, None, [wall("w", 2.45, 0.0)])["REACTION_TIME"]
    assert v.status == "not_applicable" and v.margin is None


def test_the_sensor_measures_from_the_footprint_to_the_beams_end() -> None:
    header = StreamHeader(SCHEMA_VERSION, "s", "s", 0, RATE, ROBOT, (PERSON[0][0],), 1.0)
    sensor = HazardSensor(header)
    s = scan(1.0)
    poses = np.array([[1.25, 0.0, 0.0]])
    got = sensor.clearance(s, (0.0, 0.0, 0.0), poses, np.array([0.86]))
    assert got == pytest.approx(1.0 - HALF)
    # a beam 45 degrees to the left ending 1 m from the centre: 1 m along the beam, but its
    # end point is nearer the footprint's corner than that
    left = LaserScan(-math.pi, math.pi / 4, 0.12, 3.5, np.array([3.5] * 5 + [1.0, 3.5, 3.5]))
    end = (math.cos(math.pi / 4), math.sin(math.pi / 4))
    corner = math.hypot(end[0] - HALF, end[1] - 0.153)  # ROBOT's box: 0.281 x 0.306
    got = sensor.clearance(left, (0.0, 0.0, 0.0), np.array([[end[0] + 0.25, end[1], 0.0]]),
                           np.array([0.6]))
    assert got == pytest.approx(corner) and corner < 1.0 - HALF
    # the same person out of reach of every beam: nothing seen
    assert sensor.clearance(s, (0.0, 0.0, 0.0), np.array([[1.25, 0.6, 0.0]]),
                            np.array([0.9])) == NONE_SEEN


def test_a_beam_sees_a_box_hazard_within_the_tolerance_of_its_face() -> None:
    cart = ObservedObject("cart", "dynamic", "cart", Box(0.6, 0.4), 0.9)
    header = StreamHeader(SCHEMA_VERSION, "s", "s", 0, RATE, ROBOT, (cart,), 1.0)
    sensor = HazardSensor(header)
    # the cart's face (turned 90 degrees: its 0.4 m side faces the robot) 3 cm or 10 cm
    # beyond where the forward beam ends
    for beyond, seen in ((0.03, True), (0.10, False)):
        poses = np.array([[1.0 + beyond + 0.2, 0.0, math.pi / 2]])
        got = sensor.clearance(scan(1.0), (0.0, 0.0, 0.0), poses, np.array([0.9]))
        assert (got == pytest.approx(1.0 - HALF)) if seen else got == NONE_SEEN
