"""The default specification's requirements, each shown failing on a stream that breaks it
and passing on one that does not (a test of the test), and not applicable where its premise
is absent. Synthetic streams: what the run loop records, written by hand."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from rei.runtime.messages import (
    SCHEMA_VERSION,
    GoalFacts,
    MissionEvent,
    MissionFacts,
    NavState,
    ObservedObject,
    RobotBelief,
    Sample,
    StreamHeader,
)
from rei.runtime.observation.evaluator.summary import MonitorResult
from rei.runtime.results import RESULTS_VERSION, RunSummary, Verdict, judge
from tests.observation.helpers import monitor
from tests.observation.streams import ROBOT, drive, human, wall

RATE = 10.0


@dataclass(frozen=True)
class Tick:
    """One sample: the robot's pose, its driven twist, its command, object poses."""

    pose: tuple[float, float, float]
    twist: tuple[float, float, float] = (0.0, 0.0, 0.0)
    cmd: tuple[float, float] = (0.0, 0.0)
    objects: tuple[tuple[float, float, float], ...] | None = None
    events: tuple[MissionEvent, ...] = ()
    contacts: tuple[int, ...] = ()


def facts(headings: Sequence[float | None] = (None,), cycles: int = 1,
          speed_limit: float = 0.26) -> MissionFacts:
    goals = tuple(GoalFacts(f"g{i}", 1.0 + i, 0.0, h, 0.25, math.radians(15), 60.0)
                  for i, h in enumerate(headings))
    return MissionFacts(goals, cycles, 100.0, speed_limit, 1.82, None)


def stream(placed: Sequence[tuple[ObservedObject, tuple[float, float, float]]],
           ticks: Sequence[Tick], mission: MissionFacts | None = None,
           floors: tuple[tuple[str, float, float], ...] = ()
           ) -> tuple[StreamHeader, list[Sample]]:
    h = StreamHeader(SCHEMA_VERSION, "synthetic", "synthetic", 0, RATE, ROBOT,
                     tuple(o for o, _ in placed), 1.0, floors,
                     mission_facts=mission if mission is not None else facts())
    still = np.array([p for _, p in placed], dtype=float).reshape(len(placed), 3)
    samples = []
    for i, t in enumerate(ticks):
        poses = still if t.objects is None else np.array(t.objects, dtype=float).reshape(-1, 3)
        belief = RobotBelief(t.pose, (0.0, 0.0), 3.5, None, NavState.ACTIVE, None, cmd=t.cmd)
        samples.append(Sample(i, i / RATE, t.pose, t.twist, poses, np.zeros_like(poses), belief,
                              t.events, contacts=t.contacts))
    return h, samples


def mission_events(n_ticks: int, fail: tuple[str, str] | None = None
                   ) -> dict[int, tuple[MissionEvent, ...]]:
    """begin + one task that succeeds (or fails with (cause, reason)) + end."""
    end = MissionEvent("task_fail", (n_ticks - 2) / RATE, "g0", 0, fail[1], fail[0]) if fail \
        else MissionEvent("task_success", (n_ticks - 2) / RATE, "g0", 0)
    return {0: (MissionEvent("begin", 0.0), MissionEvent("task_start", 0.0, "g0", 0)),
            n_ticks - 2: (end,), n_ticks - 1: (MissionEvent("end", (n_ticks - 1) / RATE),)}


def with_events(ticks: list[Tick], events: dict[int, tuple[MissionEvent, ...]]) -> list[Tick]:
    return [Tick(t.pose, t.twist, t.cmd, t.objects, events.get(i, ()), t.contacts)
            for i, t in enumerate(ticks)]


def run(tmp: Path, placed: Sequence[tuple[ObservedObject, tuple[float, float, float]]],
        ticks: list[Tick], mission: MissionFacts | None = None, fail: tuple[str, str] | None = None,
        floors: tuple[tuple[str, float, float], ...] = ()
        ) -> tuple[dict[str, Verdict], MonitorResult]:
    h, samples = stream(placed, with_events(ticks, mission_events(len(ticks), fail)), mission,
                        floors)
    _, result = monitor(h, samples, tmp)
    return {v.requirement: v for v in result.verdicts}, result


def summary_of(result: MonitorResult) -> RunSummary:
    return RunSummary(RESULTS_VERSION, "m", "r", 0, "test", "completed", "", 1.0,
                      result.total_utility, result.signal_counts, result.verdicts)


def driving(x0: float, x1: float, n: int, v: float) -> list[Tick]:
    """The robot drives along +x from x0 to x1, commanding and driving at ``v``."""
    return [Tick((x0 + (x1 - x0) * i / (n - 1), 0.0, 0.0), (v, 0.0, 0.0), (v, 0.0))
            for i in range(n)]


FAR_WALL = [wall("w", 5.0, 0.0)]


def test_a_clean_run_passes_and_absent_premises_are_not_applicable(tmp_path: Path) -> None:
    verdicts, result = run(tmp_path, FAR_WALL, driving(0.0, 1.0, 12, 0.2))
    status = {k: v.status for k, v in verdicts.items()}
    # one goal: neither the thesis's pair of neighbouring goals nor a back-and-forth cycle
    assert status.pop("MISSION_SIMPLE") == "not_applicable"
    assert status.pop("MISSION_SEQUENCE_CYCLE") == "not_applicable"
    assert status.pop("MISSION_WITH_HUMAN_TRAJECTORY") == "not_applicable"
    assert status.pop("HUMAN_SLOW_ZONE") == "not_applicable"
    assert status.pop("GOAL_HEADING") == "not_applicable"
    assert status.pop("REACTION_TIME") == "not_applicable"  # no people, nothing moving
    assert status.pop("COMMAND_AT_REST") == "not_applicable"  # ends 0.1 s after its goal
    assert set(status.values()) == {"pass"}, status
    assert judge(summary_of(result)) == "pass"


@pytest.mark.parametrize(("cause", "reason"), [
    ("aborted", "aborted: no path"), ("timeout", "timeout after 60 s"),
    ("position", "outside tolerance: the robot is 0.612 m from the goal, tolerance 0.25 m"),
    ("abandoned", "mission time limit of 100 s reached")])
def test_a_failed_task_fails_goals_reached_with_the_executors_reason(
        tmp_path: Path, cause: str, reason: str) -> None:
    verdicts, result = run(tmp_path, FAR_WALL, driving(0.0, 1.0, 12, 0.2),
                           fail=(cause, reason))
    goals = verdicts["MISSION_GOALS_REACHED"]
    assert goals.status == "fail"
    assert reason in goals.reason and "g0" in goals.reason
    assert goals.objects == ("g0",)
    assert goals.decided_at == pytest.approx(1.0)
    assert verdicts["GOAL_HEADING"].status == "not_applicable"
    assert judge(summary_of(result)) == "fail"


def test_a_wrong_heading_fails_goal_heading_only(tmp_path: Path) -> None:
    mission = facts(headings=(0.0,))
    ok, _ = run(tmp_path / "ok", FAR_WALL, driving(0.0, 1.0, 12, 0.2), mission)
    assert ok["GOAL_HEADING"].status == "pass"
    bad, result = run(tmp_path / "bad", FAR_WALL, driving(0.0, 1.0, 12, 0.2), mission,
                      fail=("heading", "heading off by 37.2° (tolerance 15°)"))
    assert bad["GOAL_HEADING"].status == "fail"
    assert "heading off by 37.2°" in bad["GOAL_HEADING"].reason
    assert bad["MISSION_GOALS_REACHED"].status == "pass"
    assert judge(summary_of(result)) == "fail"


def test_speed_is_judged_on_the_command_before_the_motor_clips_it(tmp_path: Path) -> None:
    ok, _ = run(tmp_path / "ok", FAR_WALL, driving(0.0, 1.0, 12, 0.26))
    assert ok["SPEED_LIMIT"].status == "pass"
    # commands 2.5x the limit; the motor clips it, so the driven speed is within the limit
    ticks = [Tick(t.pose, t.twist, (0.65, 0.0)) for t in driving(0.0, 1.0, 12, 0.26)]
    bad, _ = run(tmp_path / "cmd", FAR_WALL, ticks)
    assert bad["SPEED_LIMIT"].status == "fail"
    assert "overSpeedCommanded" in bad["SPEED_LIMIT"].reason
    spin = [Tick(t.pose, t.twist, (0.1, 3.0)) for t in driving(0.0, 1.0, 12, 0.1)]
    assert run(tmp_path / "spin", FAR_WALL, spin)[0]["SPEED_LIMIT"].status == "fail"


def test_the_missions_speed_limit_is_the_tighter_one(tmp_path: Path) -> None:
    slow = facts(speed_limit=0.1)
    verdicts, _ = run(tmp_path, FAR_WALL, driving(0.0, 1.0, 12, 0.2), slow)
    assert verdicts["SPEED_LIMIT"].status == "fail"
    assert "overSpeed" in verdicts["SPEED_LIMIT"].reason


def test_slow_zone_near_people(tmp_path: Path) -> None:
    person = [human("alice", 1.6, 0.0)]
    # robot front edge at x + 0.14; the person's edge at 1.35: at x = 0.9 the gap is 0.31 m
    fast, _ = run(tmp_path / "fast", person, driving(0.0, 0.9, 12, 0.25))
    assert fast["HUMAN_SLOW_ZONE"].status == "fail"
    assert fast["HUMAN_SLOW_ZONE"].objects == ("alice",)
    slowing = driving(0.0, 0.5, 6, 0.25) + driving(0.52, 0.9, 6, 0.1)
    slow, _ = run(tmp_path / "slow", person, slowing)
    assert slow["HUMAN_SLOW_ZONE"].status == "pass"


def test_driving_into_a_wall_is_the_robots_collision(tmp_path: Path) -> None:
    near_wall = [wall("w", 1.0, 0.0)]
    # the wall's face is at x = 0.5, the robot's front at x + 0.1405
    ticks = driving(0.0, 0.36, 10, 0.1)
    verdicts, result = run(tmp_path, near_wall, ticks)
    assert verdicts["NO_ROBOT_COLLISION"].status == "fail"
    assert verdicts["NO_ROBOT_COLLISION"].objects == ("w",)
    assert result.signal_counts.get("SIG_ROBOT_COLLISION") == 1
    stopped = driving(0.0, 0.3, 9, 0.1) + [Tick((0.3, 0.0, 0.0))]
    assert run(tmp_path / "stop", near_wall, stopped)[0]["NO_ROBOT_COLLISION"].status == "pass"


def test_a_person_walking_into_a_still_robot_is_recorded_not_blamed(tmp_path: Path) -> None:
    person = [human("bob", 2.0, 0.0)]
    # the robot stands at the origin; bob walks in from +x until he touches its front
    ticks = [Tick((0.0, 0.0, 0.0), objects=((2.0 - 1.7 * i / 9, 0.0, 0.0),)) for i in range(10)]
    ticks += [Tick((0.0, 0.0, 0.0), objects=((0.3, 0.0, 0.0),))] * 2
    verdicts, result = run(tmp_path, person, ticks)
    assert verdicts["NO_ROBOT_COLLISION"].status == "pass"
    assert result.signal_counts.get("SIG_HUMAN_WALKED_INTO_ROBOT") == 1
    # the thesis's requirements still count every collision with a person
    assert verdicts["MISSION_WITH_HUMAN_TRAJECTORY"].status == "fail"
    # the robot driving into bob is its fault
    drove = [Tick((0.0 + 0.155 * i / 9, 0.0, 0.0), (0.1, 0.0, 0.0), (0.1, 0.0))
             for i in range(10)]
    near = [human("bob", 0.55, 0.0)]
    assert run(tmp_path / "drove", near, drove)[0]["NO_ROBOT_COLLISION"].status == "fail"


def test_a_physical_contact_between_samples_is_a_collision(tmp_path: Path) -> None:
    person = [human("carol", 0.7, 0.0)]
    # sampled gap 0.7 - 0.25 - 0.1405 - 0.28 ≈ 0.03 m > eps_collision; the physics touched
    ticks = [Tick((0.28, 0.0, 0.0), (0.1, 0.0, 0.0), (0.1, 0.0))] * 3
    clean, _ = run(tmp_path / "clean", person, list(ticks))
    assert clean["NO_ROBOT_COLLISION"].status == "pass"
    touched = list(ticks)
    touched[1] = Tick(ticks[1].pose, ticks[1].twist, ticks[1].cmd, contacts=(0,))
    verdicts, _ = run(tmp_path / "touched", person, touched)
    assert verdicts["MISSION_WITH_HUMAN_TRAJECTORY"].status == "fail"
    assert verdicts["NO_ROBOT_COLLISION"].status == "fail"


def test_weaving_fails_smooth_motion_and_a_steady_turn_does_not(tmp_path: Path) -> None:
    def turning(rates: list[float]) -> list[Tick]:
        return [Tick((0.02 * i, 0.0, 0.0), (0.15, 0.0, w), (0.15, w))
                for i, w in enumerate(rates)]
    # left, right, left within 4 s while driving: an oscillating heading controller
    weave, _ = run(tmp_path / "weave", FAR_WALL, turning([0.0] * 3 + [0.5] * 5 + [-0.5] * 5
                                                          + [0.5] * 5 + [0.0] * 3))
    assert weave["SMOOTH_MOTION"].status == "fail"
    # one correction each way, 5 s apart, and a long steady turn: smooth
    smooth, _ = run(tmp_path / "smooth", FAR_WALL, turning(
        [0.0] * 3 + [0.5] * 5 + [0.0] * 50 + [-0.5] * 5 + [0.0] * 3 + [1.0] * 30 + [0.0] * 3))
    assert smooth["SMOOTH_MOTION"].status == "pass"
    # turning on the spot back and forth (not driving) is no weaving
    spot = [Tick((0.0, 0.0, 0.0), (0.0, 0.0, w), (0.0, w))
            for w in [0.5] * 5 + [-0.5] * 5 + [0.5] * 5]
    assert run(tmp_path / "spot", FAR_WALL, spot)[0]["SMOOTH_MOTION"].status == "pass"


def test_driving_off_right_after_turning_left_on_the_spot_is_no_weaving(tmp_path: Path) -> None:
    """Issue 22 (medium room 261): an arc right, a recovery's left turn on the spot, and an
    arc right again. The robot executes a command from the tick it is sent, so between two
    samples it moves with the later one's twist (the poses, interpolated linearly, say so
    too); interpolating the twist as well put a left turn while driving between the spin and
    the arc, a motion the robot never made, and SMOOTH_MOTION failed."""
    def tick(i: int, v: float, w: float) -> Tick:
        return Tick((0.02 * i, 0.0, 0.0), (v, 0.0, w), (v, w))
    recovery = [(0.0, 0.0)] * 3 + [(0.26, -0.33)] * 2 + [(0.0, 0.0)] * 5 + [(0.0, 0.69)] * 4 \
        + [(0.26, -0.64)] * 5 + [(0.0, 0.0)] * 3
    smooth, _ = run(tmp_path / "spin", FAR_WALL, [tick(i, v, w)
                                                  for i, (v, w) in enumerate(recovery)])
    assert smooth["SMOOTH_MOTION"].status == "pass"
    # the same with the left turn driven (0.4 s at 0.26 m/s): weaving
    driven = [(v if w != 0.69 else 0.26, w) for v, w in recovery]
    weave, _ = run(tmp_path / "arc", FAR_WALL, [tick(i, v, w) for i, (v, w) in enumerate(driven)])
    assert weave["SMOOTH_MOTION"].status == "fail"


def test_the_back_and_forth_requirement_applies_only_to_cycles_of_two_goals(
        tmp_path: Path) -> None:
    # thesis 5.1.2: m = (g1, g2)*
    ride = driving(0.0, 1.0, 12, 0.2)
    verdicts, _ = run(tmp_path / "a", FAR_WALL, ride, facts((None, None), cycles=2))
    assert verdicts["MISSION_SEQUENCE_CYCLE"].status == "pass"
    for name, mission in (("once", facts((None, None))), ("three", facts((None,) * 3, 2)),
                          ("one", facts(cycles=2))):
        verdicts, _ = run(tmp_path / name, FAR_WALL, ride, mission)
        assert verdicts["MISSION_SEQUENCE_CYCLE"].status == "not_applicable", name


CORRIDOR = tuple((f"c{i}", float(i), 0.0) for i in range(-1, 6))
"""Floors c-1 .. c5 at x = -1 .. 5; facts() puts goal g<i> at x = 1 + i."""


def test_the_simple_mission_is_a_pair_of_neighbouring_goals_driven_once(tmp_path: Path) -> None:
    # thesis 5.1.2 MISSION_SIMPLE: a pair of goals (g1, g2), the robot moves to the
    # neighbouring floor without collision
    ride = driving(0.0, 1.0, 12, 0.2)
    pair = facts((None, None))  # goals on c1 and c2, side by side
    verdicts, _ = run(tmp_path / "pair", FAR_WALL, ride, pair, floors=CORRIDOR)
    assert verdicts["MISSION_SIMPLE"].status == "pass"
    apart = MissionFacts((pair.goals[0], dataclasses.replace(pair.goals[1], x=4.0)), 1, 100.0,
                         0.26, 1.82, None)
    cases = {"apart": apart, "cycles": facts((None, None), cycles=2), "one": facts(),
             "three": facts((None,) * 3)}
    for name, mission in cases.items():
        verdicts, _ = run(tmp_path / name, FAR_WALL, ride, mission, floors=CORRIDOR)
        assert verdicts["MISSION_SIMPLE"].status == "not_applicable", name
    # where it applies it judges collisions as before: driving into the wall fails it
    crash = driving(0.0, 4.5, 30, 0.2)
    verdicts, _ = run(tmp_path / "crash", FAR_WALL, crash, pair, floors=CORRIDOR)
    assert verdicts["MISSION_SIMPLE"].status == "fail"


def test_personal_space_is_measured_while_moving(tmp_path: Path) -> None:
    person = [human("dan", 1.6, 0.0)]
    ticks = driving(0.0, 0.5, 6, 0.1) + [Tick((0.9, 0.0, 0.0))]
    _, result = run(tmp_path, person, ticks)
    moving = result.measurements["min_distance_to_human_moving"]
    assert moving == pytest.approx(1.6 - 0.25 - 0.1405 - 0.5, abs=1e-3)
    assert result.measurements["min_distance_to_human"] < moving


def test_the_laser_requirements_allow_the_lasers_accuracy_and_no_more(tmp_path: Path) -> None:
    """GEOM_CLOSE_LASER_CORRECT: the robot drives up to a wall (face at x = 1.5, its front at
    x + 0.1405) and stops 0.24 m short, just inside ε_close; its forward beam reads the true
    range, a range 4 cm long (within laser_tolerance, 0.05 m, though above ε_close), 8 cm long,
    or nothing at all (a blind laser)."""
    poses = [(1.12 * i / 19, 0.0, 0.0) for i in range(20)] + [(1.12, 0.0, 0.0)] * 15
    true_range = [1.5 - x for x, _, _ in poses]  # from the footprint centre (the mount)

    def verdict(ranges: list[float], name: str) -> str:
        h, samples = drive([wall("w", 2.0, 0.0)], poses, laser=ranges)
        _, result = monitor(h, samples, tmp_path / name)
        return {v.requirement: v.status for v in result.verdicts}["GEOM_CLOSE_LASER_CORRECT"]

    assert verdict(true_range, "exact") == "pass"
    assert verdict([r + 0.04 for r in true_range], "within") == "pass"
    assert verdict([r + 0.08 for r in true_range], "off") == "fail"
    assert verdict([3.5] * len(poses), "blind") == "fail"
