"""A social walker pressed against a wall does not slide along it into the robot (issue 25).

With humans kept upright, a walker that gave way stood pressed against a wall; the robot
passed it a few centimetres off and stopped; the walker then slid along the wall into the
robot (SIG_HUMAN_WALKED_INTO_ROBOT, medium room_0037 r0 on wp-contact: the walker at
(-5.74, -0.25) against the wall below it, the robot stopping 0.46 m away up and ahead of
it, the walker's measured velocity 0.14-0.45 m/s along the wall, towards the robot).
``keep_clear`` took away the walker's velocity towards the robot, which turned the rest
into the wall; the contact took that part away, and what was left ran along the wall into
the robot. Now the velocity into a wall the walker touches goes first, and the two limits
hold together. Shown with the real Animator (a wall as the simulator's contact: the part
of the motion into it is dropped) and with ``keep_clear`` alone.
"""

from __future__ import annotations

import math

import numpy as np

from rei.lang.room.spline import CatmullRom
from rei.runtime.simulation.animator.agent import Agent
from rei.runtime.simulation.animator.bodies import Animated, Reactions
from rei.runtime.simulation.animator.engine import Animator
from rei.runtime.simulation.animator.social_force import SocialForce, keep_clear
from rei.runtime.simulation.animator.walls import wall_normals

WALL_TOP = -0.5
"""The wall fills y <= -0.5 (a box 1 m thick, 20 m long)."""
WALLS = np.array([[0.0, WALL_TOP - 0.5, 0.0, 10.0, 0.5]])
HUMAN_RADIUS = 0.25
ROBOT_RADIUS = 0.2077
ROBOT = (0.29, 0.19, 2.7)
"""Where the robot stopped in room_0037 r0, from the walker: up and ahead of it, 7 cm
from its footprint."""


def _pinned(social: SocialForce, seconds: float = 20.0) -> float:
    """A social walker at (0, -0.25), against the wall, whose path runs on along the wall
    (+x) past the robot standing at ``ROBOT``; the real Animator drives it at the control
    rate, and the wall stops it at y = -0.25 as the simulator's contact does (the part of
    the motion into the wall is dropped). Its smallest gap to the robot's footprint."""
    spline = CatmullRom(np.array([0.0, 10.0]), np.array([[0.0, -0.25], [8.0, -0.25]]), False)
    paths = Animator([Animated(1, spline, True, "social", radius=HUMAN_RADIUS)],
                     physics_rate=10.0, robot_radius=ROBOT_RADIUS,
                     reactions=Reactions(social=social), walls=WALLS)
    x, y, smallest = 0.0, WALL_TOP + HUMAN_RADIUS, math.inf
    for step in range(int(seconds * 10)):
        paths.correct(step, [(x, y, 0.0)], ROBOT, (0.0, 0.0, 0.0))
        _, vx, vy, _ = paths.commands(step)[0]
        x, y = x + vx / 10.0, max(y + vy / 10.0, WALL_TOP + HUMAN_RADIUS)
        smallest = min(smallest, math.hypot(x - ROBOT[0], y - ROBOT[1])
                       - HUMAN_RADIUS - ROBOT_RADIUS)
    return smallest


def test_a_walker_pinned_against_a_wall_does_not_slide_into_the_robot() -> None:
    # The model before: kept clear of the robot without the wall, it slides into it.
    assert _pinned(SocialForce(wall_stop=False)) < 0.0
    # Now: it never comes closer than it stood.
    start = math.hypot(ROBOT[0], ROBOT[1] + 0.25) - HUMAN_RADIUS - ROBOT_RADIUS
    assert _pinned(SocialForce()) >= start - 1e-9


def test_keep_clear_holds_the_wall_and_the_robot_together() -> None:
    model, robot = SocialForce(), Agent(ROBOT[0], ROBOT[1], ROBOT_RADIUS)
    x, y = 0.0, WALL_TOP + HUMAN_RADIUS
    touching = wall_normals(WALLS, x, y, HUMAN_RADIUS + model.clearance_margin)
    assert touching == [(0.0, -1.0)]
    # Without the wall: nothing towards the robot, but turned into the wall; the wall takes
    # that away and what is left runs towards the robot.
    vx, vy = keep_clear(model, x, y, 0.8, 0.0, HUMAN_RADIUS, [robot])
    assert vy < 0.0
    nx, ny = ROBOT[0] - x, ROBOT[1] - y
    assert vx * nx > 0.0  # vy is dropped by the contact: vx alone closes in
    # With it: neither into the wall nor towards the robot (here: it stands).
    vx, vy = keep_clear(model, x, y, 0.8, 0.0, HUMAN_RADIUS, [robot], touching)
    assert vy >= -1e-12 and vx * nx + vy * ny <= 1e-9
    # Away from the robot along the wall is kept as it was.
    assert keep_clear(model, x, y, -0.8, 0.0, HUMAN_RADIUS, [robot], touching) == (-0.8, 0.0)
    # Leaving the wall is kept too; a wall it does not touch takes nothing.
    assert keep_clear(model, x, y, 0.0, 0.3, HUMAN_RADIUS, [], touching) == (0.0, 0.3)
    assert wall_normals(WALLS, x, y + 0.2, HUMAN_RADIUS + model.clearance_margin) == []


def test_wall_normals_point_to_the_nearest_point_of_a_turned_box() -> None:
    # A 1 m square turned 45 degrees at the origin: its corner at (0.707, 0).
    walls = np.array([[0.0, 0.0, math.pi / 4.0, 0.5, 0.5]])
    (nx, ny), = wall_normals(walls, 1.0, 0.0, 0.3)
    assert math.isclose(nx, -1.0) and abs(ny) < 1e-12
    # Off its face: straight towards the face, (-1, -1)/sqrt(2).
    (nx, ny), = wall_normals(walls, 0.5, 0.5, 0.3)
    assert math.isclose(nx, -math.sqrt(0.5)) and math.isclose(ny, -math.sqrt(0.5))
    assert wall_normals(walls, 2.0, 0.0, 0.3) == []
    assert wall_normals(np.zeros((0, 5)), 0.0, 0.0, 1.0) == []
