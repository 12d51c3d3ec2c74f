"""Moving humans and dynamic objects on Catmull-Rom splines (thesis 4.2), scripted or
reacting to the robot (yielding, social force), with seeded per-run variations."""

from rei.lang.room.spline import CatmullRom
from rei.runtime.animator.animator import Animated, Animator, Reactions, spline_of
from rei.runtime.animator.reactive import SocialForce, YieldRule
from rei.runtime.animator.variation import HumanVariation, draw_variations

__all__ = ["Animated", "Animator", "CatmullRom", "HumanVariation", "Reactions", "SocialForce",
           "YieldRule", "draw_variations", "spline_of"]
