"""Recovery behaviours of the `reference` navigator, driven by synthetic observations.

A tiny stand-in world (no simulator): the robot integrates its own commands as a unicycle
(or stays pinned), and its laser is ray-cast against boxes and circles here, some of which
the navigator's static map does not know (a shelf it did not expect, a person standing).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from rei.catalogue import DriveSpec, LaserSpec
from rei.runtime.messages import LaserScan, NavState
from rei.runtime.robot import NavGoal, Observation, VelocityCommand
from rei.runtime.robot.behaviours import reported
from rei.runtime.robot.contract import ControllerContext, MapObstacle
from rei.runtime.robot.navigator.recovery import footprint_gaps, motion_is_safe
from rei.runtime.robot.navigator.reference import ABORT_GRACE, BLOCKED_AFTER, ReferenceNavigator

DT = 0.1
HALF = (0.1405, 0.153)  # turtlebot3_waffle footprint 0.281 x 0.306
DRIVE = DriveSpec(0.26, 1.82, 0.287, 0.033)
LASER = LaserSpec(360, 0.12, 3.5, 5.0, 2 * math.pi)


@dataclass(frozen=True)
class Box:
    x0: float
    y0: float
    x1: float
    y1: float


@dataclass(frozen=True)
class Circle:
    x: float
    y: float
    r: float


def corridor_walls() -> list[Box]:
    """1 m wall tiles around a corridor 1 m wide: free for -0.5 < x < 6.5, -0.5 < y < 0.5."""
    tiles = [(k, y) for k in range(-1, 8) for y in (-1, 1)] + [(-1, 0), (7, 0)]
    return [Box(x - 0.5, y - 0.5, x + 0.5, y + 0.5) for x, y in tiles]


def context_of(walls: list[Box]) -> ControllerContext:
    obstacles = tuple(MapObstacle(f"w{i}", "wall", (b.x0 + b.x1) / 2, (b.y0 + b.y1) / 2, 0.0,
                                  "box", b.x1 - b.x0, b.y1 - b.y0) for i, b in enumerate(walls))
    xs = [b.x0 for b in walls] + [b.x1 for b in walls]
    ys = [b.y0 for b in walls] + [b.y1 for b in walls]
    return ControllerContext(robot_size=(2 * HALF[0], 2 * HALF[1]), drive=DRIVE, laser=LASER,
                             start_pose=(0.0, 0.0, 0.0), obstacles=obstacles,
                             bounds=(min(xs), min(ys), max(xs), max(ys)), tile_size=1.0,
                             control_rate=1 / DT, seed=0)


def scan_of(pose: tuple[float, float, float], boxes: list[Box],
            circles: list[Circle]) -> LaserScan:
    """A 360-beam scan from ``pose`` (mount at the centre): exact ray casting."""
    n = LASER.beams
    inc = LASER.fov / n
    ang = pose[2] - LASER.fov / 2 + inc * np.arange(n)
    dx, dy = np.cos(ang), np.sin(ang)
    best = np.full(n, LASER.max_range)
    with np.errstate(divide="ignore", invalid="ignore"):
        for b in boxes:  # slab method
            tx0, tx1 = (b.x0 - pose[0]) / dx, (b.x1 - pose[0]) / dx
            ty0, ty1 = (b.y0 - pose[1]) / dy, (b.y1 - pose[1]) / dy
            near = np.maximum(np.minimum(tx0, tx1), np.minimum(ty0, ty1))
            far = np.minimum(np.maximum(tx0, tx1), np.maximum(ty0, ty1))
            hit = (far >= near) & (far > 0)
            best = np.where(hit, np.minimum(best, np.maximum(near, 0.0)), best)
    for c in circles:
        ox, oy = pose[0] - c.x, pose[1] - c.y
        bq = ox * dx + oy * dy
        disc = bq * bq - (ox * ox + oy * oy - c.r * c.r)
        t = -bq - np.sqrt(np.maximum(disc, 0.0))
        best = np.where((disc >= 0) & (t > 0), np.minimum(best, t), best)
    return LaserScan(-LASER.fov / 2, inc, LASER.min_range, LASER.max_range, best)


def gap_to(pose: tuple[float, float, float], boxes: list[Box], circles: list[Circle]) -> float:
    """Smallest distance from the robot's footprint to any box or circle (negative: overlap)."""
    pts = []
    for b in boxes:  # the boxes' nearest points to the robot stand for them
        pts.append((min(max(pose[0], b.x0), b.x1), min(max(pose[1], b.y0), b.y1)))
    for c in circles:
        d = math.hypot(pose[0] - c.x, pose[1] - c.y)
        if d > 0:
            pts.append((c.x + (pose[0] - c.x) * c.r / d, c.y + (pose[1] - c.y) * c.r / d))
    world = np.array(pts)
    cs, sn = math.cos(pose[2]), math.sin(pose[2])
    rel = np.stack((cs * (world[:, 0] - pose[0]) + sn * (world[:, 1] - pose[1]),
                    -sn * (world[:, 0] - pose[0]) + cs * (world[:, 1] - pose[1])), axis=1)
    gap = float(footprint_gaps(rel, HALF, np.zeros((1, 3))).min())
    # Nearest point of a circle to the centre is not always nearest to the rectangle:
    # sample the circles' rims too.
    for c in circles:
        a = np.linspace(0, 2 * math.pi, 72, endpoint=False)
        rim = np.stack((c.x + c.r * np.cos(a), c.y + c.r * np.sin(a)), axis=1)
        rr = np.stack((cs * (rim[:, 0] - pose[0]) + sn * (rim[:, 1] - pose[1]),
                       -sn * (rim[:, 0] - pose[0]) + cs * (rim[:, 1] - pose[1])), axis=1)
        gap = min(gap, float(footprint_gaps(rr, HALF, np.zeros((1, 3))).min()))
    return gap


@dataclass
class Drive:
    commands: list[VelocityCommand]
    states: list[NavState]
    times: list[float]
    gaps: list[float]
    navigator: ReferenceNavigator
    doing: list[tuple[str, ...]]
    """What the navigator reported doing after each step (behaviours.reported)."""


def drive(walls: list[Box], unknown: list[Box], people: list[Circle], goal: NavGoal,
          start: tuple[float, float, float], seconds: float, pinned: bool = False,
          people_until: float = math.inf,
          navigator: type[ReferenceNavigator] = ReferenceNavigator) -> Drive:
    """Run the navigator on the stand-in world until the goal ends or ``seconds`` pass."""
    nav = navigator()
    nav.reset(context_of(walls))
    nav.send_goal(goal)
    pose = list(start)
    out = Drive([], [], [], [], nav, [])
    t = 0.0
    while t < seconds:
        here = people if t < people_until else []
        p = (pose[0], pose[1], pose[2])
        cmd = nav.step(Observation(t, p, (0.0, 0.0), scan_of(p, walls + unknown, here), t))
        out.commands.append(cmd)
        out.times.append(t)
        if not pinned:
            pose[0] += cmd.linear * math.cos(pose[2]) * DT
            pose[1] += cmd.linear * math.sin(pose[2]) * DT
            pose[2] = math.remainder(pose[2] + cmd.angular * DT, math.tau)
        out.gaps.append(gap_to((pose[0], pose[1], pose[2]), walls + unknown, here))
        feedback = nav.feedback()
        state = feedback.state
        out.states.append(state)
        out.doing.append(reported(feedback.message))
        t = round(t + DT, 9)
        if state in (NavState.SUCCEEDED, NavState.ABORTED, NavState.PREEMPTED):
            break
    return out


def within_limits(cmds: list[VelocityCommand]) -> bool:
    return all(abs(c.linear) <= DRIVE.max_linear + 1e-9 and abs(c.angular) <= DRIVE.max_angular
               + 1e-9 for c in cmds)


# -- the checks of a recovery motion --------------------------------------------------------

def test_backing_up_is_refused_when_something_is_right_behind() -> None:
    behind = np.array([[-HALF[0] - 0.03, 0.0]])
    assert not motion_is_safe(behind, HALF, -0.1, 0.0)
    assert motion_is_safe(behind, HALF, 0.1, 0.0)


def test_a_spin_is_refused_when_a_corner_would_sweep_into_a_point() -> None:
    # 2 cm off the front face, right of centre: turning left swings the front right corner
    # (0.207 m from the centre) through it; turning right swings that corner away.
    ahead = np.array([[HALF[0] + 0.02, -0.1]])
    assert not motion_is_safe(ahead, HALF, 0.0, 0.9)
    assert motion_is_safe(ahead, HALF, 0.0, -0.9)


def test_moving_away_from_a_point_already_too_close_stays_possible() -> None:
    touching = np.array([[HALF[0] + 0.005, 0.0]])
    assert motion_is_safe(touching, HALF, -0.1, 0.0)
    assert not motion_is_safe(touching, HALF, 0.05, 0.0)


# -- the navigator ---------------------------------------------------------------------------

def test_a_pinned_robot_backs_up_and_turns_before_it_aborts_within_the_limit() -> None:
    # A shelf the map does not know 12 cm in front, and the goal behind: the local planner can
    # neither drive on nor (with its margin) turn round; the robot never moves, whatever it does.
    walls = corridor_walls()
    shelf = [Box(3.26, -0.45, 3.45, 0.45)]
    run = drive(walls, shelf, [], NavGoal("g", 0.0, 0.0, None, 0.3, 200.0), (3.0, 0.0, 0.0),
                80.0, pinned=True)
    assert run.states[-1] == NavState.ABORTED
    end = run.times[-1]
    assert BLOCKED_AFTER < end <= BLOCKED_AFTER + ABORT_GRACE + DT
    backed = [t for t, c in zip(run.times, run.commands, strict=True) if c.linear < 0]
    turned = [t for t, c in zip(run.times, run.commands, strict=True)
              if c.linear == 0 and c.angular != 0]
    assert backed and turned and min(backed) < end and min(turned) < end
    assert {"backup", "spin"} <= set(run.navigator._recovery.log)
    assert within_limits(run.commands)
    # ... and says so in its feedback, on the steps that back up and turn
    said = {name for doing in run.doing for name in doing}
    assert {"recovery.backup", "recovery.spin"} <= said, said
    for t, command, doing in zip(run.times, run.commands, run.doing, strict=True):
        if doing == ("recovery.backup",):
            assert command.linear < 0, t
        if doing == ("recovery.spin",):
            assert command.linear == 0 and command.angular != 0, t


def test_a_person_standing_in_a_corridor_for_good_aborts_the_goal_without_contact() -> None:
    person = [Circle(2.5, 0.0, 0.25)]  # 25 cm either side: the robot (31 cm wide) cannot pass
    run = drive(corridor_walls(), [], person, NavGoal("g", 5.0, 0.0, None, 0.3, 200.0),
                (0.0, 0.0, 0.0), 80.0)
    assert run.states[-1] == NavState.ABORTED
    assert BLOCKED_AFTER < run.times[-1] <= BLOCKED_AFTER + ABORT_GRACE + DT
    assert min(run.gaps) > 0.0  # never touched the person or a wall
    assert {"backup", "replan", "replan_reduced", "wait"} <= set(run.navigator._recovery.log)
    assert within_limits(run.commands)
    said = {name for doing in run.doing for name in doing}
    assert {"recovery.backup", "recovery.replan", "recovery.replan_reduced", "recovery.wait",
            "slow_for_person"} <= said, said
    # no way round the person: no re-plan around them was adopted
    assert "replan_unmapped" not in said
    # an aborted goal's feedback is the reason, not a behaviour
    assert run.doing[-1] == ()


def test_a_person_who_walks_on_lets_the_robot_reach_the_goal() -> None:
    person = [Circle(2.5, 0.0, 0.25)]
    run = drive(corridor_walls(), [], person, NavGoal("g", 5.0, 0.0, None, 0.3, 200.0),
                (0.0, 0.0, 0.0), 80.0, people_until=20.0)
    assert run.states[-1] == NavState.SUCCEEDED
    assert run.navigator._recovery.log  # it had to recover, and did not give up
    assert min(run.gaps) > 0.0


def test_recoveries_are_deterministic() -> None:
    person = [Circle(2.5, 0.0, 0.25)]
    runs = [drive(corridor_walls(), [], person, NavGoal("g", 5.0, 0.0, None, 0.3, 200.0),
                  (0.0, 0.0, 0.0), 40.0).commands for _ in range(2)]
    assert runs[0] == runs[1]


@pytest.mark.slow
def test_a_generated_small_room_that_used_to_abort_now_completes(tmp_path: Path) -> None:
    """room_0003 of `rei-gen rooms --preset small --count 6 --seed 0`: the navigator got
    stuck next to a shelf on the second cycle and aborted the goal (before recoveries)."""
    import argparse

    from rei.lang.commands import rooms
    from rei.runtime.runs.session import run_into

    parser = argparse.ArgumentParser()
    rooms.register(parser.add_subparsers())
    args = parser.parse_args(["rooms", "-o", str(tmp_path / "suite"), "--preset", "small",
                              "--count", "6", "--seed", "0", "--quiet"])
    assert args.func(args) == 0
    summary, _ = run_into(tmp_path / "suite" / "room_0003.mission", tmp_path / "run",
                          monitor=False)
    assert summary.outcome == "completed", summary.measurements["tasks"]
    assert summary.measurements["tasks_succeeded"] == 4
    assert summary.measurements["collisions"] == 0
