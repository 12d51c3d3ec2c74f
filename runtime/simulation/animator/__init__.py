"""Moving humans and dynamic objects on Catmull-Rom splines (thesis 4.2), scripted or
reacting to the robot (yielding, social force), with seeded per-run variations: the
``Animator`` (engine.py) moves the animated bodies (bodies.py).

How reactive humans respond to the robot:

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

The reactions are pure functions of poses and velocities; the parameters are plain frozen
records. Nothing here may import the simulator (pybullet) or the monitor, or judge the robot.
"""

from rei.lang.room.spline import CatmullRom
from rei.runtime.simulation.animator.bodies import Animated, Reactions, spline_of
from rei.runtime.simulation.animator.engine import Animator
from rei.runtime.simulation.animator.social_force import SocialForce
from rei.runtime.simulation.animator.variation import HumanVariation, draw_variations
from rei.runtime.simulation.animator.yielding import YieldRule

__all__ = ["Animated", "Animator", "CatmullRom", "HumanVariation", "Reactions", "SocialForce",
           "YieldRule", "draw_variations", "spline_of"]
