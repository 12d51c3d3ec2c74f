"""The yielding rule: how a ``yielding`` human makes way for the robot.

``yielding``: a human slows down, then stands, while the robot's footprint is in a cone
ahead of it along its walking direction, and walks on when the way is clear. Its path
time only advances while it walks, so it resumes where it stopped. A human that has stood
for ``patience`` seconds with the robot still in its way gives way: it steps out of the
robot's way (where it has room, below) until the robot is ``give_way_gap`` away, stands
there until the robot is out of its way (at most ``give_way_time``: the robot's goal may
be where the human stands), and returns to its path. Without that, a human standing in a one-tile
passage and a robot waiting for it to move would wait for each other until the goal
times out. A human that stands because it has nowhere to walk (before its start, at the
end of an open path) gives way the same way to a robot waiting within ``slow_gap`` of it
on any side (``gap_beside``): a path that ends on the robot's goal otherwise keeps the
human on the goal for ever, and any navigator fails that goal (issue 22: a medium-preset
walker stood on goal_2 from 31 s until the reference aborted it at 227 s).
A human steps only where it has room (``way_aside``: across the robot's heading, else
straight away from the robot or up to 90 degrees off that, wherever the place
``aside_room`` ahead of its step keeps its radius from every wall); with nowhere to step
it turns back along its path (the package docstring). Stepping aside into a wall, it stood
beside the robot, came back, yielded and stepped into the wall again, and both waited until the goal
aborted (issue 25, a MAP-Elites room: the walker's loop ran along a wall through the
robot's goal). At the turning point of a path that goes out and back, turning back leads
the same way, into the robot: there only a step away helps (a TPE room of issue 25's
protocol, where the walker stood at its turning point beside a wall's end).

Turning back is told in the package docstring; the turning back itself, and the stepping
aside, are the animator's (engine.py): here are the rule's parameters and the pure functions
of poses it decides by. This module must never import pybullet or the monitor, nor judge the
robot.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rei.runtime.simulation.animator.agent import Agent, Vec


@dataclass(frozen=True)
class YieldRule:
    cone_half_angle: float = math.radians(40.0)
    """Radians either side of the walking direction in which the robot is 'in the way'."""
    slow_gap: float = 1.0
    """m between footprints below which a human in whose way the robot is slows down."""
    stop_gap: float = 0.45
    """m between footprints at which it stands still."""
    patience: float = 3.0
    """s a human stands with the robot in its way before it gives way."""
    give_way_speed: float = 0.4
    """m/s at which a human giving way steps away from the robot."""
    give_way_gap: float = 1.5
    """m between footprints at which a human giving way stops stepping back."""
    give_way_time: float = 6.0
    """s a human stands aside at most before it walks its path again (and yields afresh)."""
    aside_room: float = 0.5
    """m: a human gives way by stepping only where the place this far ahead of its step
    keeps its radius from every wall (``way_aside``); with nowhere to step, it turns back
    (0: it steps across the robot's heading without looking: the model before issue 25)."""
    turn_back_time: float = 6.0
    """s of its path a human that turned back walks backwards before it turns round again
    (0: it never turns back, it always steps aside: the model before issue 25's deadlocks)."""


def gap_in_the_way(rule: YieldRule, x: float, y: float, radius: float, direction: Vec,
                   robot: Agent) -> float | None:
    """The gap (m) between the footprints when the robot is in the cone ahead of the human,
    None when it is not. ``direction`` is the walking direction (need not be unit length;
    zero means the human is not walking, and nothing is in its way)."""
    norm = math.hypot(*direction)
    if norm < 1e-9:
        return None
    ex, ey = direction[0] / norm, direction[1] / norm
    dx, dy = robot.x - x, robot.y - y
    ahead = dx * ex + dy * ey
    side = abs(dx * ey - dy * ex)
    # The footprint is in the cone when its nearest point is: widen the cone by both radii.
    reach = radius + robot.radius
    if ahead <= -reach or side > math.tan(rule.cone_half_angle) * max(ahead, 0.0) + reach:
        return None
    return math.hypot(dx, dy) - reach


def gap_beside(rule: YieldRule, x: float, y: float, radius: float, robot: Agent) -> float | None:
    """The gap (m) between the footprints when the robot is within ``give_way_gap`` of a
    standing human on any side, None when it is farther: a human with nowhere to walk is in
    the way of a robot whichever side it comes from (the robot waits on it within
    ``slow_gap``; a human giving way steps back to ``give_way_gap``)."""
    gap = math.hypot(robot.x - x, robot.y - y) - radius - robot.radius
    return gap if gap < max(rule.slow_gap, rule.give_way_gap) else None


def speed_share(rule: YieldRule, gap: float | None) -> float:
    """1 to walk at full path speed, 0 to stand, for the robot ``gap`` metres ahead."""
    if gap is None or gap >= rule.slow_gap:
        return 1.0
    if gap <= rule.stop_gap:
        return 0.0
    return (gap - rule.stop_gap) / (rule.slow_gap - rule.stop_gap)


def yield_factor(rule: YieldRule, x: float, y: float, radius: float, direction: Vec,
                 robot: Agent) -> float:
    """How much of its path speed a human walks at with the robot where it is."""
    return speed_share(rule, gap_in_the_way(rule, x, y, radius, direction, robot))
