"""The social force model: how a ``social`` human walks round the robot and the others.

``social``: the social force model of Helbing and Molnár (Phys. Rev. E 51, 4282, 1995):
a driving force relaxes the human's velocity towards its desired velocity (towards a
target point moving along its spline) over the relaxation time; the robot and the other
humans repel it with a force decaying exponentially with the gap between footprints
(the form of Helbing, Farkas and Vicsek, Nature 407, 487, 2000), weighted by how far
ahead the other is (the anisotropy of Helbing and Molnár's angle of sight). The gap is
measured with Helbing and Molnár's elliptical distance b, which accounts for the other's
step v * step_time, so a robot driving towards a human repels it earlier than one
standing or driving away.
Two additions keep a fair human from walking into a robot at any walking speed
(rei_lang's WALKING_SPEEDS, 0.5-1.4 m/s): the repulsion is scaled by the human's path
speed over ``reference_speed`` (its driving force grows with that speed, so a fixed
strength let a human at 1.3 m/s settle against the robot's footprint), and a human never
closes the gap to another body faster than (gap - clearance_margin) / clearance_time
(``keep_clear``): it stops short of the robot instead of pressing into it. Nor does it
walk into a wall or fixed object it touches (``wall_normals``), and both limits hold
together: keeping clear of a robot up and ahead of a human pressed against a wall turned
its velocity into the wall, the contact took that part away, and the rest slid it along
the wall into the robot (issue 25, with humans kept upright).
Walls are not part of the force: the spline keeps clear of them, and a pushed human
meets them as real contacts. So a human that meets the robot with a wall on its right
would turn into the wall and retreat ahead of the robot for as long as it comes on (a
reference run herded a walker 3 m along a wall onto its goal, issue 25): a human held
back from its way for ``patience`` seconds tries the other side (``pass_side``), as
people do when the first side is blocked. Walls and fixed objects decide the side from
the start where one side is too narrow (``fits_past``): passing a standing robot on the
side of a wall it did not fit past, a human slid along the wall, which turned its way
round the robot into the robot (issue 22, medium room 123). A human held back on the
other side too for ``patience`` turns back along its path: with a wall on one side and the
waiting robot's footprint on the other, one whose loop crossed the robot's goal stood
0.3 m from the goal for 30 s while the robot, 0.34 m from it, waited for it (issue 25).
Turning back also ends a herding: a robot driving at a human held it back on both sides
as it retreated, once 3 m off its loop through a doorway, where it stood for good against
the wall between it and its path, beside the goal (issue 25); now it turns back after
6 s, its target runs the other way, and it walks off round the robot. A robot on the
move no longer drives a human ahead of it at all (``away_from_approach``): its push along
its heading is turned across it, and a human passes a crossing robot behind it (a
walker that passed in front of the robot was driven 2.2 m off its loop into a corner
beside the goal, issue 25). A hard bound on how
far a human lets itself be pushed from its target (1.2 m: it gave no more ground there)
was tried and dropped: pressed by the robot into a corner of a wall and a box 1 m off its
path, a human held there stood for good, and the reference failed that search room.

Everything here is a pure function of poses and velocities (the dodge memory, the sides a
human chose a moment ago, is handed in as a ``Dodge`` and kept by the animator); the
parameters are plain frozen records. This module must never import pybullet or the monitor,
nor judge the robot.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rei.runtime.simulation.animator.agent import Agent, Vec
from rei.runtime.simulation.animator.walls import room_aside, wall_distance

KEEP_CLEAR_PASSES = 8
"""Rounds of projections ``keep_clear`` makes before it gives up and stands the human (two
limits at an angle meet within a few)."""


@dataclass(frozen=True)
class SocialForce:
    relaxation_time: float = 0.5
    """s: how fast the velocity relaxes to the desired one (Helbing and Molnár: 0.5 s)."""
    strength: float = 6.0
    """A, m/s^2: repulsion per unit mass at touching footprints for a human walking at
    ``reference_speed`` or slower (Helbing and Molnár's V0/sigma is 7 m/s^2 between
    pedestrians' centres); scaled up in proportion for a faster one."""
    range: float = 0.5
    """B, m: the repulsion's decay length. Helbing and Molnár's sigma is 0.3 m between
    pedestrians; a robot is avoided from farther away, so a human at walking speed starts
    its detour about 1.5 m before the robot."""
    anisotropy: float = 0.35
    """lambda: weight of an agent straight behind (1 straight ahead), Helbing et al. 2000."""
    passing: float = 1.0
    """Share of the repulsion turned to the human's right: a head-on approach to a standing
    robot is otherwise an equilibrium where the human stands until its target gives up."""
    max_speed_factor: float = 1.3
    """v_max / v0: how much faster than its path a human hurries (Helbing and Molnár: 1.3)."""
    step_time: float = 1.0
    """s: the others' step v * step_time that shapes the elliptical distance (Helbing and
    Molnár use 2 s between pedestrians; 1 s keeps a robot crossing far ahead harmless)."""
    reference_speed: float = 0.8
    """m/s: the walking speed ``strength`` is set for. A faster human's driving force is
    larger in proportion, (v0 - v) / relaxation_time, so its repulsion is scaled by
    v0 / reference_speed (never below 1): the gap it keeps from the robot is then the same
    at every walking speed, where a fixed strength let a human at 1.3 m/s settle against
    the robot's footprint and touch it."""
    clearance_time: float = 0.5
    """s: a human closes the gap to another body at most at (gap - clearance_margin) /
    clearance_time, so it slows to a stop before touching (people do not walk into a robot
    they see); its motion across is kept, so it slides round."""
    clearance_margin: float = 0.05
    """m: the gap at which a human stops closing in (pybullet reports a contact a little
    before the footprints meet)."""
    patience: float = 3.0
    """s a human walks at less than ``held_share`` of its desired speed towards where it
    wants to go before it switches the side it passes on."""
    held_share: float = 0.25
    """Share of its desired speed, along its desired direction, below which a human counts
    as held back."""
    turn_back_time: float = 6.0
    """s of its path a human walks backwards after it was held back on both sides for its
    ``patience`` each, before it turns round again (0: it never turns back)."""
    dodge: float = 1.0
    """Share of the robot's repulsion along its heading that is turned across it while it
    comes at the human against (or across) the human's way (``away_from_approach``): a
    person in front of an advancing robot steps off its line, to the side it stands on (the
    other where that has no ``dodge_room``), instead of retreating ahead of it; and a human
    passes a robot crossing its way behind it, not in front (0: the model before issue 25's
    herded walker, which the robot drove 2.2 m ahead of it into a corner beside its goal)."""
    dodge_room: float = 0.5
    """m: a human steps off the robot's line to a side only where the place this far that
    way keeps its radius from every wall (``room_aside``)."""
    dodge_speed: float = 0.05
    """m/s: a robot slower than this is standing, and repels the human straight away."""
    dodge_memory: float = 2.0
    """s a human keeps the sides it chose to step off a robot's line and to pass it on
    (``dodge_sides``) after the robot last came at it within ``dodge_near`` (0: it chooses
    them afresh at every step). Chosen afresh at every step, both flipped from step to step: a
    human on the line of a crawling robot, whose speed hovered about ``dodge_speed``,
    stepped left, right and left again in front of it, and the robot weaving round it
    failed SMOOTH_MOTION (issue 25's protocol, seed 3). People commit to a side, as the
    reference navigator does (``TURN_COMMITMENT``)."""
    dodge_near: float = 1.0
    """m between footprints within which a human commits to the sides it chose; farther
    off it weighs them afresh at every step (committed from 3 m off, a human that chose
    before the robot turned its way passed it in front)."""
    wall_stop: bool = True
    """Whether a human's velocity into a wall or fixed object it touches (within
    ``clearance_margin``) is dropped before it is kept clear of the others (``keep_clear``);
    False: the model before issue 25's walkers that slid along a wall into the robot."""
    cutoff: float = 3.0
    """m between footprints beyond which another agent exerts no force (cheap, and smooth
    enough: A exp(-3/0.5) is 0.015 m/s^2)."""


def social_acceleration(model: SocialForce, x: float, y: float, vx: float, vy: float,
                        radius: float, desired: Vec, others: list[Agent],
                        walking_speed: float = 0.0, side: float = 1.0,
                        robot: Agent | None = None, dodge: Dodge | None = None) -> Vec:
    """dv/dt of a human at (x, y) with velocity (vx, vy) that wants to walk at ``desired``
    along a path walked at ``walking_speed`` (m/s; the repulsion's scale, see
    ``SocialForce.reference_speed``), passing what is ahead on its right (``side`` 1) or
    its left (-1). ``robot`` (one of ``others``) is the one body it steps off the line of
    and passes as ``dodge`` says (``dodge_sides``, ``away_from_approach``; None: it
    repels like any other)."""
    strength = model.strength * max(1.0, walking_speed / model.reference_speed)
    ax = (desired[0] - vx) / model.relaxation_time
    ay = (desired[1] - vy) / model.relaxation_time
    hx, hy = heading_of((vx, vy), desired)
    for other in others:
        dx, dy = x - other.x, y - other.y
        dist = math.hypot(dx, dy)
        if dist < 1e-9:
            continue
        gap = elliptical_distance(dx, dy, other.vx * model.step_time,
                                  other.vy * model.step_time) - radius - other.radius
        if gap > model.cutoff:
            continue
        nx, ny = dx / dist, dy / dist
        # cos of the angle between where the human heads and where the other is.
        cos_phi = -(nx * hx + ny * hy)
        weight = model.anisotropy + (1.0 - model.anisotropy) * (1.0 + cos_phi) / 2.0
        push = strength * math.exp(-gap / model.range) * weight
        passes = side
        if other is robot and dodge is not None:
            (nx, ny), passes = away_from_approach(model, (nx, ny), other, desired, dodge)
        ax += push * nx
        ay += push * ny
        if cos_phi > 0.0:  # only what is ahead deflects the human sideways, to its right
            turn = passes * model.passing * push * cos_phi
            ax += turn * hy
            ay += turn * -hx
    return ax, ay


@dataclass(frozen=True)
class Dodge:
    """How a human gets past a robot coming at it (``dodge_sides``): the side of the robot's
    line it steps off to and the side it passes the robot on (each 1 right, -1 left; the
    first of the robot's heading, the second of the human's), and the robot's and the
    human's headings they were chosen for (unit vectors)."""

    steps: float
    passes: float
    towards: Vec
    walking: Vec


def dodge_sides(model: SocialForce, walls: np.ndarray | None, x: float, y: float,
                radius: float, velocity: Vec, desired: Vec, robot: Agent, side: float,
                kept: Dodge | None = None) -> Dodge | None:
    """The sides a human at (x, y) walking at ``velocity`` (or wanting to, ``desired``)
    takes to get past a robot on the move (None while the robot stands: it repels straight away, and
    the human passes it on ``side``); ``kept``: the sides it chose a moment ago, which it
    keeps (``SocialForce.dodge_memory``) unless the robot or the human has turned away from
    the heading they were chosen for by more than a right angle.

    Pushed straight away from a robot that comes at it, a human retreats along the robot's
    heading, ahead of it, for as long as it comes on: issue 25's TPE room, where the robot
    drove a walker 2.2 m off its loop into a corner beside its goal and waited there for
    it until the goal aborted. People step off the line of what comes at them: to the side
    of the robot's line the human stands on, or to the other where only that has
    ``dodge_room``. And a human passes a robot crossing its way (at 30 degrees or more)
    behind it: passing in front of a moving robot on the side it moves to led the human
    along with it."""
    speed = math.hypot(robot.vx, robot.vy)
    if model.dodge <= 0.0 or speed < model.dodge_speed:
        return None
    ux, uy = robot.vx / speed, robot.vy / speed
    lx, ly = -uy, ux  # the robot's left
    hx, hy = heading_of(velocity, desired)
    if kept is not None and kept.towards[0] * ux + kept.towards[1] * uy >= 0.0 \
            and kept.walking[0] * hx + kept.walking[1] * hy >= 0.0:
        steps, passes, towards, walking = kept.steps, kept.passes, kept.towards, kept.walking
    else:
        crossing = hy * ux - hx * uy  # the robot's heading along the human's right
        passes = side if abs(crossing) < 0.5 else (-1.0 if crossing > 0.0 else 1.0)
        steps = 1.0 if (x - robot.x) * lx + (y - robot.y) * ly >= 0.0 else -1.0
        towards, walking = (ux, uy), (hx, hy)
    if walls is not None and not room_aside(walls, x, y, radius, (steps * lx, steps * ly),
                                            model.dodge_room) \
            and room_aside(walls, x, y, radius, (-steps * lx, -steps * ly), model.dodge_room):
        steps = -steps
    return Dodge(steps, passes, towards, walking)


def away_from_approach(model: SocialForce, away: Vec, robot: Agent, desired: Vec,
                       dodge: Dodge) -> tuple[Vec, float]:
    """Which way a robot on the move repels a human (a unit vector; ``away`` is straight
    away from it) that gets past it as ``dodge`` says, and the side it passes it on: the
    part of the push along the robot's heading is turned across it, to ``dodge.steps``
    (``dodge`` of it), in full when the robot comes against the human's way (``desired``),
    not at all when it follows it (it then pushes the human on along its way). A robot
    that stopped a moment ago (``dodge_memory``) pushes straight away, and the human
    passes it on the side it chose."""
    speed = math.hypot(robot.vx, robot.vy)
    if speed < model.dodge_speed:
        return away, dodge.passes
    ux, uy = robot.vx / speed, robot.vy / speed
    ahead = away[0] * ux + away[1] * uy
    if ahead <= 0.0:
        return away, dodge.passes
    dx, dy = _unit(desired)
    share = model.dodge * ahead * (1.0 - max(0.0, ux * dx + uy * dy))
    lx, ly = -dodge.steps * uy, dodge.steps * ux
    tx = away[0] + share * (lx - ux)
    ty = away[1] + share * (ly - uy)
    norm = math.hypot(tx, ty)
    return ((tx / norm, ty / norm) if norm > 1e-9 else away), dodge.passes


def keep_clear(model: SocialForce, x: float, y: float, vx: float, vy: float, radius: float,
               others: list[Agent], touching: Sequence[Vec] = ()) -> Vec:
    """The velocity (vx, vy) with its component towards each other body limited to
    (gap - clearance_margin) / clearance_time (none at all closer than the margin) and none
    into a wall it is ``touching`` (unit vectors towards each, ``wall_normals``); the
    component across is kept, so the human slides round rather than stands.

    The limits hold together: the wall would take away the part into it anyway, and what
    it left of a velocity turned off the robot into the wall slid along the wall into the
    robot (issue 25: a walker pinned against a wall beside a passing robot). They are met by
    projecting onto each in turn until all hold; a human they leave no way out stands."""
    limits = [(n, 0.0) for n in touching]
    for other in others:
        dx, dy = other.x - x, other.y - y
        dist = math.hypot(dx, dy)
        if dist < 1e-9:
            continue
        gap = dist - radius - other.radius - model.clearance_margin
        limits.append(((dx / dist, dy / dist), max(gap, 0.0) / model.clearance_time))
    for _ in range(KEEP_CLEAR_PASSES):
        done = True
        for (nx, ny), allowed in limits:
            closing = vx * nx + vy * ny
            if closing > allowed:
                vx -= (closing - allowed) * nx
                vy -= (closing - allowed) * ny
                done = done and closing - allowed < 1e-12
        if done:
            return vx, vy
    if any(vx * nx + vy * ny > allowed + 1e-9 for (nx, ny), allowed in limits):
        return 0.0, 0.0
    return vx, vy


def held_back(model: SocialForce, vx: float, vy: float, desired: Vec) -> bool:
    """Whether a human walking at (vx, vy) makes less than ``held_share`` of the headway it
    wants along ``desired`` (never, for one that wants to stand)."""
    want = math.hypot(*desired)
    if want < 1e-6:
        return False
    return (vx * desired[0] + vy * desired[1]) / want < model.held_share * want


def pass_side(model: SocialForce, side: float, held_for: float) -> float:
    """The side (1 right, -1 left) a human passes on after ``held_for`` seconds held back."""
    return -side if held_for >= model.patience else side


def fits_past(model: SocialForce, walls: np.ndarray, x: float, y: float, radius: float,
              desired: Vec, robot: Agent, side: float) -> bool:
    """Whether a human at (x, y) walking towards ``desired`` fits past the robot on ``side``
    (1 its right, -1 its left): the place beside the robot it would pass through, the
    clearance margin off the robot's footprint, keeps its radius from every wall (``walls``
    as in ``wall_distance``). True when the robot is not ahead of it within the social
    force's cutoff (nothing to pass)."""
    norm = math.hypot(*desired)
    dx, dy = robot.x - x, robot.y - y
    if norm < 1e-9 or dx * desired[0] + dy * desired[1] <= 0.0 \
            or math.hypot(dx, dy) - radius - robot.radius > model.cutoff:
        return True
    hx, hy = desired[0] / norm, desired[1] / norm
    beside = robot.radius + radius + model.clearance_margin
    return wall_distance(walls, robot.x + side * hy * beside,
                         robot.y - side * hx * beside) >= radius


def elliptical_distance(dx: float, dy: float, sx: float, sy: float) -> float:
    """Helbing and Molnár's b: the semi-minor axis of the ellipse through the human, with
    foci at the other's position and one step (sx, sy) ahead of it; the plain distance for
    a standing other, shorter for one coming closer, longer for one moving away."""
    step = math.hypot(sx, sy)
    if step < 1e-9:
        return math.hypot(dx, dy)
    major = math.hypot(dx, dy) + math.hypot(dx - sx, dy - sy)
    return 0.5 * math.sqrt(max(major * major - step * step, 0.0))


def limit_speed(vx: float, vy: float, limit: float) -> Vec:
    speed = math.hypot(vx, vy)
    if speed <= limit or speed < 1e-12:
        return vx, vy
    return vx * limit / speed, vy * limit / speed


def heading_of(velocity: Vec, desired: Vec) -> Vec:
    """Where a human heads (a unit vector): along its velocity while it walks, else where it
    wants to walk."""
    speed = math.hypot(*velocity)
    if speed > 1e-6:
        return velocity[0] / speed, velocity[1] / speed
    return _unit(desired)


def _unit(v: Vec) -> Vec:
    norm = math.hypot(*v)
    return (v[0] / norm, v[1] / norm) if norm > 1e-9 else (0.0, 0.0)
