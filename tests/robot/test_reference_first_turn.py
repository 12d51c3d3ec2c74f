"""The `reference` navigator's first turn on the spot (issue 22): a goal whose path starts
behind the robot is turned towards in place, then driven to straight, where the local
planner alone looped round on its tightest forward arc. On the stand-in world of
test_reference_recovery (no simulator): the robot integrates its own commands."""

from __future__ import annotations

import math

import numpy as np

from rei.runtime.messages import NavState
from rei.runtime.robot import NavGoal
from rei.runtime.robot.navigator.reference import ALIGN_FIRST
from tests.robot.arcs_around import ArcsAround
from tests.robot.test_reference_recovery import DRIVE, DT, Box, Drive, drive


def open_room() -> list[Box]:
    """1 m wall tiles round a free square -2.5 < x, y < 2.5."""
    tiles = {(x, y) for x in range(-3, 4) for y in (-3, 3)} | {
        (x, y) for x in (-3, 3) for y in range(-3, 4)}
    return [Box(x - 0.5, y - 0.5, x + 0.5, y + 0.5) for x, y in sorted(tiles)]


BEHIND = NavGoal("behind", -0.5, 0.0, None, 0.3, 60.0)
"""1.5 m straight behind the robot at (1, 0) facing +x."""


def path_length(run: Drive) -> float:
    return sum(abs(c.linear) * DT for c in run.commands)


def test_a_goal_behind_is_turned_to_on_the_spot_then_driven_to_straight() -> None:
    start = (1.0, 0.0, math.pi - 2.3)  # the goal 2.3 rad off the heading, as in room_0216
    run = drive(open_room(), [], [], BEHIND, start, 40.0)
    assert run.states[-1] == NavState.SUCCEEDED
    # on the spot, at 0.6 of the turn limit once the smoother let it get there
    first = run.commands[:8]
    assert all(c.linear == 0.0 and 0.0 < abs(c.angular) <= 0.6 * DRIVE.max_angular + 1e-9
               for c in first)
    assert abs(first[-1].angular) == 0.6 * DRIVE.max_angular
    # about the straight line less the 0.1 m the reference stops short of the goal
    assert path_length(run) < 1.1 * 1.4
    looping = drive(open_room(), [], [], BEHIND, start, 40.0, navigator=ArcsAround)
    assert looping.states[-1] == NavState.SUCCEEDED
    assert path_length(looping) > path_length(run) + 0.3


def test_the_first_turn_is_deterministic_and_ends_facing_the_path() -> None:
    runs = [drive(open_room(), [], [], BEHIND, (1.0, 0.0, 0.3), 40.0) for _ in range(2)]
    assert runs[0].commands == runs[1].commands
    first_drive = next(k for k, c in enumerate(runs[0].commands) if c.linear > 0)
    heading = 0.3 + sum(c.angular * DT for c in runs[0].commands[:first_drive])
    assert abs(math.remainder(heading - math.pi, math.tau)) <= ALIGN_FIRST + 0.6 * DT * \
        DRIVE.max_angular


def test_a_turn_on_the_spot_into_something_is_left_to_the_local_planner() -> None:
    # A shelf the map knows 3 cm beside the robot's left side: turning in place would swing
    # a rear corner (0.207 m from the centre) into it.
    shelf = Box(0.3, 0.153 + 0.03, 1.7, 0.6)
    run = drive([*open_room(), shelf], [], [], BEHIND, (1.0, 0.0, 0.0), 5.0)
    spins = [c for c in run.commands[:5] if c.linear == 0.0 and abs(c.angular) ==
             0.6 * DRIVE.max_angular]
    assert spins == []
    assert min(run.gaps) > 0.0
    assert np.isfinite(run.gaps).all()
