"""How reactive humans respond to the robot: the yielding rule and the social force model.

Scripted humans walk into a robot that stands in their way, so a correct navigator fails
as often as a human-blind one; reactive humans make the test fair.

* ``yielding`` (yielding.py): a human slows down, then stands, while the robot is in its
  way, and gives way (steps aside or turns back) when the robot waits on it.
* ``social`` (social_force.py): the social force model of Helbing and Molnár, with the
  additions that keep a fair human from walking into a robot, and the dodge memory.
* walls.py: where a human has room among the walls and fixed objects; agent.py: the other
  bodies a human reacts to.

Turning back (both behaviours): a human walks its path backwards (its path time runs back)
for ``turn_back_time`` seconds, or to the start of an open path, and then forwards again,
yielding afresh; one that turned back and is held back again turns forwards at once (the
robot followed it). It keeps to its path, so it needs no map, and it walks away from the
robot rather than standing beside it: a robot waiting for it gets the way free, and one
waiting at its goal on the human's path gets the goal (the human comes back later, as
people do). Nothing here forbids a path over a goal or makes a human avoid the robot's way:
a robot that drives into a human that stands or turns round is still to blame.

This module only gathers those modules' names where the code imported them from before the
split (issue 34); it holds nothing of its own. Everything there is a pure function of poses
and velocities; the parameters are plain frozen records. None of them may import the
simulator (pybullet) or the monitor, or judge the robot.
"""

from rei.runtime.simulation.animator.agent import Agent, Vec
from rei.runtime.simulation.animator.social_force import (
    KEEP_CLEAR_PASSES,
    Dodge,
    SocialForce,
    away_from_approach,
    dodge_sides,
    elliptical_distance,
    fits_past,
    heading_of,
    held_back,
    keep_clear,
    limit_speed,
    pass_side,
    social_acceleration,
)
from rei.runtime.simulation.animator.walls import room_aside, wall_distance, wall_normals, way_aside
from rei.runtime.simulation.animator.yielding import (
    YieldRule,
    gap_beside,
    gap_in_the_way,
    speed_share,
    yield_factor,
)

__all__ = [
    "Agent",
    "Dodge",
    "KEEP_CLEAR_PASSES",
    "SocialForce",
    "Vec",
    "YieldRule",
    "away_from_approach",
    "dodge_sides",
    "elliptical_distance",
    "fits_past",
    "gap_beside",
    "gap_in_the_way",
    "heading_of",
    "held_back",
    "keep_clear",
    "limit_speed",
    "pass_side",
    "room_aside",
    "social_acceleration",
    "speed_share",
    "wall_distance",
    "wall_normals",
    "way_aside",
    "yield_factor",
]
