"""The defective navigators of the bug-finding benchmark (bench/defects): each keeps the
controller contract (but for the two whose defect the checker itself reports) and really has
the one defect its docstring names, seen here at the level of single steps, never a campaign.
The reference navigator's slow zone is checked here too, as the defect-free side of NoSlowZone.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from bench.defects import DEFECTS, Defect
from bench.defects.control import (
    CLEARING_SPIN,
    ExceedsDriveLimit,
    IgnoresMissionSpeed,
    InvertedApproachScaling,
    NoSlowZone,
    OscillatingHeading,
    SpinsWhenTurning,
)
from bench.defects.localisation import OdometryOffset
from bench.defects.mission import (
    AbortsEveryGoal,
    ClaimsSuccessEarly,
    IgnoresGoalHeading,
    NeverReportsSuccess,
    SkipsSecondGoal,
)
from bench.defects.perception import BlindSector, IgnoresHumans
from bench.defects.planning import FootprintTooSmall, NeverClearsObstacles
from bench.defects.timing import (
    DROPOUT_LENGTH,
    LATENCY,
    SCAN_DELAY,
    CommandDropout,
    ControlLatency,
    DelayedScans,
    StaleScans,
)
from rei.runtime.messages import LaserScan, NavState
from rei.runtime.robot import (
    ControllerContext,
    NavGoal,
    Observation,
    VelocityCommand,
    check_controller,
    load_controller,
    make_controller,
)
from rei.runtime.robot.conformance import checker_context
from rei.runtime.robot.navigator.reference import (
    HORIZON,
    MARGIN,
    SLOW_ZONE_SPEED,
    ReferenceNavigator,
)

BEAMS = 90
"""The checker's laser: 90 beams over the full circle from -pi, 0.12-3.5 m."""
START = (1.0, 2.0, 0.0)
"""The middle of the checker's empty 5 m x 5 m room, facing +x (2.5 m to the east wall)."""
FAR_GOAL = NavGoal("far", 3.5, 2.0, None, 0.3, 60.0)

# What the checker itself says about the two defects it is built to notice.
CONFORMANCE_FINDS = {
    "exceeds-drive-limit": "exceeded the drive limits",
    "never-reports-success": "did not end",
}


def scan(hits: dict[float, float] | None = None) -> LaserScan:
    """A scan of the checker's laser seeing nothing but ``{bearing (rad): range (m)}``."""
    ranges = np.full(BEAMS, 3.5)
    step = 2 * math.pi / BEAMS
    for bearing, r in (hits or {}).items():
        ranges[int(round((bearing + math.pi) / step)) % BEAMS] = r
    return LaserScan(-math.pi, step, 0.12, 3.5, ranges)


def started(nav: ReferenceNavigator, goal: NavGoal = FAR_GOAL,
            context: ControllerContext | None = None) -> ReferenceNavigator:
    nav.reset(context or checker_context())
    nav.send_goal(goal)
    return nav


def drive(nav: ReferenceNavigator, steps: int, pose: tuple[float, float, float] = START,
          hits: dict[float, float] | None = None, t0: float = 0.0) -> list[VelocityCommand]:
    """Commands for ``steps`` steps at 10 Hz, the robot held at ``pose`` (a new scan each)."""
    out = []
    for k in range(steps):
        t = t0 + 0.1 * k
        out.append(nav.step(Observation(t, pose, (0.0, 0.0), scan(hits), t)))
    return out


def drive_moving(nav: ReferenceNavigator, steps: int,
                 pose: tuple[float, float, float] = START) -> tuple[float, float]:
    """Steps at 10 Hz in the empty room, the robot moving as commanded (a unicycle); the
    distance driven and the radians turned on the spot until the goal ended."""
    x, y, yaw = pose
    driven = turned = 0.0
    for k in range(steps):
        t = 0.1 * k
        cmd = nav.step(Observation(t, (x, y, yaw), (0.0, 0.0), scan(), t))
        if nav.feedback().state != NavState.ACTIVE:
            break
        driven += abs(cmd.linear) * 0.1
        if cmd.linear == 0.0:
            turned += abs(cmd.angular) * 0.1
        x += cmd.linear * 0.1 * math.cos(yaw)
        y += cmd.linear * 0.1 * math.sin(yaw)
        yaw = math.remainder(yaw + cmd.angular * 0.1, math.tau)
    return driven, turned


PERSON_LEFT = {math.pi / 2: 0.6}
"""A person 0.6 m to the robot's left, far from every wall: an unmapped laser point."""


@pytest.mark.parametrize("defect", DEFECTS, ids=lambda d: d.name)
def test_defects_keep_the_contract_or_the_checker_names_their_defect(defect: Defect) -> None:
    controller = make_controller(defect.spec)
    assert controller.name == defect.name
    problems = check_controller(controller)
    expected = CONFORMANCE_FINDS.get(defect.name)
    if expected is None:
        assert problems == []
    else:
        assert problems and all(expected in p for p in problems), problems


@pytest.mark.parametrize("defect", DEFECTS, ids=lambda d: d.name)
def test_every_defect_says_what_it_imitates_and_what_should_catch_it(defect: Defect) -> None:
    doc = type(load_controller(defect.spec)).__doc__ or ""
    assert doc.startswith("Defect: ") and "Imitates: " in doc and "Expected catcher: " in doc


def test_the_defect_names_are_unique() -> None:
    assert len({d.name for d in DEFECTS}) == len(DEFECTS) >= 14


# -- the reference's slow zone, the defect-free side of NoSlowZone -----------------------------

def test_the_reference_slows_down_near_an_unmapped_point_and_no_slow_zone_does_not() -> None:
    free = max(c.linear for c in drive(started(ReferenceNavigator()), 5))
    near = max(c.linear for c in drive(started(ReferenceNavigator()), 5, hits=PERSON_LEFT))
    defect = max(c.linear for c in drive(started(NoSlowZone()), 5, hits=PERSON_LEFT))
    assert free > SLOW_ZONE_SPEED + 0.05
    assert 0.0 < near <= SLOW_ZONE_SPEED + 1e-9
    assert defect > SLOW_ZONE_SPEED + 0.05


def test_a_wall_the_map_explains_does_not_slow_the_reference() -> None:
    # The robot 0.6 m from the south wall's face, seeing it to its right.
    pose = (1.0, 0.1, 0.0)
    wall = {-math.pi / 2: 0.6 - 1e-3}
    nav = started(ReferenceNavigator(), NavGoal("east", 3.5, 0.1, None, 0.3, 60.0))
    assert max(c.linear for c in drive(nav, 5, pose, wall)) > SLOW_ZONE_SPEED + 0.05


def test_a_person_against_a_wall_slows_the_reference_and_the_wall_alone_does_not() -> None:
    """Issue 25 (room_0127): points 0.1 m in front of the south wall are within
    UNMAPPED_BEYOND of it, but the map leaves their beams free to the wall: a person stands
    there. The wall itself, read up to 3 cm short (three times the laser's noise), is the map."""
    pose = (1.0, 0.6, 0.0)  # the south wall's face 1.1 m to the robot's right
    right = [-math.pi / 2 + k * 2 * math.pi / BEAMS for k in (-1, 0, 1)]
    person = {b: (1.1 - 0.1) / math.cos(b + math.pi / 2) for b in right}
    wall = {b: (1.1 - 0.03) / math.cos(b + math.pi / 2) for b in right}
    goal = NavGoal("east", 3.5, 0.6, None, 0.3, 60.0)
    near = max(c.linear for c in drive(started(ReferenceNavigator(), goal), 5, pose, person))
    alone = max(c.linear for c in drive(started(ReferenceNavigator(), goal), 5, pose, wall))
    assert 0.0 < near <= SLOW_ZONE_SPEED + 1e-9
    assert alone > SLOW_ZONE_SPEED + 0.05


def _wall_behind_while_driving(nav: ReferenceNavigator) -> float:
    """The slow zone's end after driving east at 0.26 m/s with the west wall 0.8 m behind,
    seen by a scan taken at t = 0 that reaches the navigator at 0.2 s (a laser period late)
    and is used until 0.3 s (-inf: never in the slow zone)."""
    started(nav)
    wall = {math.pi + k * 2 * math.pi / BEAMS: 0.8 / math.cos(k * 2 * math.pi / BEAMS)
            for k in (-2, -1, 0, 1, 2)}
    late = scan(wall)
    for k in range(4):
        t = 0.1 * k
        nav.step(Observation(t, (0.3 + 0.26 * t, 2.0, 0.0), (0.26, 0.0),
                             late if k >= 2 else None, 0.0 if k >= 2 else None))
    return nav._slow_until


def test_a_scan_is_compared_with_the_map_from_the_pose_it_was_taken_at() -> None:
    """Read from the pose of the step 0.2 s later, the wall behind came 5 cm nearer than the
    map, beyond SHADOW_TOLERANCE, and seemed a person: the whole of a search room's mission at
    the slow speed."""
    assert _wall_behind_while_driving(ReferenceNavigator()) == -math.inf


def test_a_scan_read_from_the_pose_of_the_step_takes_the_wall_for_a_person(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The check above can fail: the stale pose puts the robot in its slow zone."""
    monkeypatch.setattr(ReferenceNavigator, "_pose_at", lambda self, time, now: now)
    assert _wall_behind_while_driving(ReferenceNavigator()) > 0.0


# -- perception ----------------------------------------------------------------------------

def test_ignores_humans_drops_unmapped_points_only() -> None:
    nav = started(IgnoresHumans())
    obs = Observation(0.0, START, (0.0, 0.0), scan({**PERSON_LEFT, math.pi: 1.45}), 0.0)
    nav.step(obs)
    points = nav._laser_points(obs)
    # The west wall 1.45 m behind stays; the person goes.
    assert len(points) == 1 and points[0, 0] < -1.0


def test_blind_sector_drops_points_between_60_and_120_degrees_left() -> None:
    nav = started(BlindSector())
    hits = {math.radians(90): 0.6, math.radians(30): 0.6, math.radians(-90): 0.6}
    obs = Observation(0.0, START, (0.0, 0.0), scan(hits), 0.0)
    nav.step(obs)
    points = nav._laser_points(obs)
    bearings = np.degrees(np.arctan2(points[:, 1], points[:, 0]))
    # The beams nearest 30 and -90 degrees stay, the one nearest 90 goes.
    assert len(points) == 2 and not ((bearings > 60) & (bearings < 120)).any()


# -- timing --------------------------------------------------------------------------------

def test_stale_scans_acts_on_a_scan_it_should_have_replaced() -> None:
    """A wall of points 0.3 m ahead (16 cm from the front) appears in the second scan: the
    reference does not drive into it (at most it creeps on at a speed whose roll-out still
    keeps its margin from the wall), the stale navigator still acts on the first, empty scan."""
    wall = {math.radians(a): 0.3 / math.cos(math.radians(a)) for a in range(-40, 41, 4)}
    room = 0.3 - checker_context().robot_size[0] / 2 - MARGIN
    for nav, expect_into in ((ReferenceNavigator(), False), (StaleScans(), True)):
        started(nav)
        drive(nav, 1)
        cmd = drive(nav, 1, hits=wall, t0=0.1)[0]
        assert (cmd.linear * HORIZON > room) == expect_into, (nav.name, cmd)


def test_control_latency_delays_every_command_by_half_a_second() -> None:
    reference = drive(started(ReferenceNavigator()), 12)
    delayed = drive(started(ControlLatency()), 12)
    lag = round(LATENCY / 0.1)
    assert reference[0].linear > 0.0
    assert all(c == VelocityCommand(0.0, 0.0) for c in delayed[:lag])
    assert delayed[lag:] == reference[:len(reference) - lag]


def test_command_dropout_holds_the_last_delivered_command_through_each_outage() -> None:
    reference = drive(started(ReferenceNavigator()), 20)
    dropped = drive(started(CommandDropout()), 20)
    outage = round(DROPOUT_LENGTH / 0.1)
    # the first outage is at the start: nothing delivered yet, the base stands
    assert all(c == VelocityCommand(0.0, 0.0) for c in dropped[:outage])
    assert dropped[outage:20] == reference[outage:20]  # delivered until the next outage
    wall = {math.radians(a): 0.3 / math.cos(math.radians(a)) for a in range(-40, 41, 4)}
    nav = started(CommandDropout())
    drive(nav, 20)
    # an obstacle appears right at the next outage (t = 2.0 s): it keeps driving on
    held = drive(nav, 3, hits=wall, t0=2.0)
    assert all(c == held[0] and c.linear > 0.0 for c in held)


def test_delayed_scans_acts_on_a_scan_taken_0_6_s_ago() -> None:
    wall = {math.radians(a): 0.3 / math.cos(math.radians(a)) for a in range(-40, 41, 4)}
    late = round(SCAN_DELAY / 0.1)
    room = 0.3 - checker_context().robot_size[0] / 2 - MARGIN
    for nav, expect_into in ((ReferenceNavigator(), False), (DelayedScans(), True)):
        started(nav)
        drive(nav, late)
        # the wall is there now; the delayed navigator still sees the empty room of 0.6 s ago
        cmd = drive(nav, 1, hits=wall, t0=0.1 * late)[0]
        assert (cmd.linear * HORIZON > room) == expect_into, (nav.name, cmd)


# -- control -------------------------------------------------------------------------------

def test_exceeds_drive_limit_commands_more_than_the_drive_allows() -> None:
    ctx = checker_context()
    fastest = max(c.linear for c in drive(started(ExceedsDriveLimit(), context=ctx), 10))
    assert fastest > ctx.drive.max_linear * 1.2


def test_ignores_mission_speed_drives_faster_than_the_mission_allows() -> None:
    ctx = dataclasses.replace(checker_context(), max_speed=0.1)
    keeps = max(c.linear for c in drive(started(ReferenceNavigator(), context=ctx), 10))
    ignores = max(c.linear for c in drive(started(IgnoresMissionSpeed(), context=ctx), 10))
    assert keeps <= 0.1 + 1e-9 < 0.15 < ignores


def test_oscillating_heading_triples_the_angular_command() -> None:
    goal = NavGoal("north-east", 3.0, 4.0, None, 0.3, 60.0)
    reference = drive(started(ReferenceNavigator(), goal), 5)
    defect = drive(started(OscillatingHeading(), goal), 5)
    wmax = checker_context().drive.max_angular
    assert any(abs(c.angular) > 0.05 for c in reference)
    for r, d in zip(reference, defect, strict=True):
        assert d.linear == r.linear
        assert d.angular == pytest.approx(float(np.clip(3.0 * r.angular, -wmax, wmax)))


def test_inverted_approach_scaling_crawls_far_from_the_goal_and_not_near_it() -> None:
    vmax = checker_context().drive.max_linear
    reference = drive(started(ReferenceNavigator()), 10)
    crawl = drive(started(InvertedApproachScaling()), 10)
    # 2.5 m from the goal the reference cruises; the defect drives at 0.6 / 2.5 of that,
    # on the reference's arcs.
    assert max(c.linear for c in reference) == pytest.approx(vmax)
    for r, d in zip(reference, crawl, strict=True):
        assert d.linear == pytest.approx(r.linear * 0.6 / 2.5)
        assert d.angular == pytest.approx(r.angular * 0.6 / 2.5)
    # 0.5 m from it (within 0.6 m) it does what the reference does.
    near = (FAR_GOAL.x - 0.5, FAR_GOAL.y, 0.0)
    assert drive(started(InvertedApproachScaling()), 3, near) == \
        drive(started(ReferenceNavigator()), 3, near)


def test_spins_when_turning_turns_a_full_turn_more_at_a_goal_with_a_heading() -> None:
    """At the goal facing north, the goal's heading east: the reference turns the quarter
    turn and succeeds; the defect's progress checker sees a second without translation and
    spins a full turn first (and again while the quarter turn's slow end lasts)."""
    goal = dataclasses.replace(FAR_GOAL, yaw=0.0)
    facing_north = (goal.x, goal.y, math.pi / 2)
    turns = {}
    for nav in (ReferenceNavigator(), SpinsWhenTurning()):
        driven, turns[nav.name] = drive_moving(started(nav, goal), 600, facing_north)
        assert nav.feedback().state == NavState.SUCCEEDED and driven == 0.0, nav.name
    assert turns["reference"] == pytest.approx(math.pi / 2, abs=0.1)
    assert turns["spins-when-turning"] >= CLEARING_SPIN + math.pi / 2 - 0.1
    # a goal it drives to in a straight line, without turning on the spot: no spin at all
    for nav in (ReferenceNavigator(), SpinsWhenTurning()):
        driven, turned = drive_moving(started(nav), 600)
        assert nav.feedback().state == NavState.SUCCEEDED and turned == 0.0, nav.name


# -- planning and localisation -------------------------------------------------------------

def test_footprint_too_small_plans_for_half_the_robot_without_inflation_cost() -> None:
    reference, defect = started(ReferenceNavigator()), started(FootprintTooSmall())
    assert defect._radius == pytest.approx(reference._radius / 2)
    # Next to the south wall the reference's edges cost more than the defect's.
    cell = defect._cell(1.0, -0.25)
    east = (cell[0] + 1, cell[1])
    assert defect._graph.weight(cell, east) == pytest.approx(1.0)
    assert (reference._reduced_graph().weight(cell, east) or 0.0) > 1.5


def test_never_clears_obstacles_plans_round_a_person_who_has_left() -> None:
    """A person stands 1 m ahead on the straight way to the goal for one scan, then is gone:
    the reference's path stays straight (its plan is the static map's), the defect re-plans
    round the place the person left."""
    person_ahead = {0.0: 1.0}
    paths = {}
    for nav in (ReferenceNavigator(), NeverClearsObstacles()):
        started(nav)
        drive(nav, 1, hits=person_ahead)
        drive(nav, 2, t0=0.1)  # the person has gone
        assert nav._path is not None
        paths[nav.name] = nav._path
    off_line = {name: float(np.abs(path[:, 1] - START[1]).max()) for name, path in paths.items()}
    assert off_line["reference"] < 0.15
    assert off_line["never-clears-obstacles"] > 0.4


def test_odometry_offset_does_not_know_it_has_arrived() -> None:
    at_goal = (FAR_GOAL.x, FAR_GOAL.y, 0.0)
    for nav, state in ((ReferenceNavigator(), NavState.SUCCEEDED),
                       (OdometryOffset(), NavState.ACTIVE)):
        drive(started(nav), 1, at_goal)
        assert nav.feedback().state == state, nav.name


# -- mission logic -------------------------------------------------------------------------

def test_ignores_goal_heading_succeeds_facing_the_wrong_way() -> None:
    goal = dataclasses.replace(FAR_GOAL, yaw=0.0)
    facing_north = (goal.x, goal.y, math.pi / 2)
    for nav, state in ((ReferenceNavigator(), NavState.ACTIVE),
                       (IgnoresGoalHeading(), NavState.SUCCEEDED)):
        drive(started(nav, goal), 1, facing_north)
        assert nav.feedback().state == state, nav.name


def test_aborts_every_goal_stands_still() -> None:
    nav = started(AbortsEveryGoal())
    assert drive(nav, 3) == [VelocityCommand(0.0, 0.0)] * 3
    assert nav.feedback().state == NavState.ABORTED


def test_claims_success_early_half_a_metre_short() -> None:
    short = (FAR_GOAL.x - 0.45, FAR_GOAL.y, 0.0)
    for nav, state in ((ReferenceNavigator(), NavState.ACTIVE),
                       (ClaimsSuccessEarly(), NavState.SUCCEEDED)):
        drive(started(nav), 1, short)
        assert nav.feedback().state == state, nav.name


def test_never_reports_success_stays_active_at_its_goal() -> None:
    at_goal = (FAR_GOAL.x, FAR_GOAL.y, 0.0)
    nav = started(NeverReportsSuccess())
    assert drive(nav, 20, at_goal)[-1] == VelocityCommand(0.0, 0.0)
    assert nav.feedback().state == NavState.ACTIVE


def test_skips_second_goal_reports_it_without_moving() -> None:
    for nav, state in ((ReferenceNavigator(), NavState.ACTIVE),
                       (SkipsSecondGoal(), NavState.SUCCEEDED)):
        drive(started(nav), 2)
        nav.send_goal(NavGoal("second", 3.5, 4.0, None, 0.3, 60.0))
        drive(nav, 1, t0=0.2)
        assert nav.feedback().state == state, nav.name
