"""Moving humans and dynamic objects on Catmull-Rom splines (thesis 4.2), scripted or
reacting to the robot (yielding, social force), with seeded per-run variations."""

from rei.lang.room.spline import CatmullRom
from rei.runtime.simulation.animator.bodies import Animated, Reactions, spline_of
from rei.runtime.simulation.animator.engine import Animator
from rei.runtime.simulation.animator.social_force import SocialForce
from rei.runtime.simulation.animator.variation import HumanVariation, draw_variations
from rei.runtime.simulation.animator.yielding import YieldRule

__all__ = ["Animated", "Animator", "CatmullRom", "HumanVariation", "Reactions", "SocialForce",
           "YieldRule", "draw_variations", "spline_of"]
