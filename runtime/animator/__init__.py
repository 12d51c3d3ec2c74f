"""Moving humans and dynamic objects on Catmull-Rom splines (thesis 4.2)."""

from rei.runtime.animator.animator import Animated, Animator, spline_of
from rei.runtime.animator.spline import CatmullRom

__all__ = ["Animated", "Animator", "CatmullRom", "spline_of"]
