"""The `reference` navigator as it was before issue 22's fix: a goal whose path starts behind
it is left to the local planner, which loops round on its tightest forward arc instead of
turning on the spot first. Scenes that search found with that navigator (a table's corner, a
walker held back) are replayed with it, so their "before" side still shows what they were
found for; tests/observation/test_efficiency.py shows the loop itself."""

from __future__ import annotations

import numpy as np

from rei.runtime.robot import VelocityCommand
from rei.runtime.robot.navigator.reference import ReferenceNavigator


class ArcsAround(ReferenceNavigator):
    """The reference without its first turn on the spot towards a path behind it (nor the
    side held near people of issue 25, which came later: the scenes replayed with it were
    found without it)."""

    hold_near_people = False
    smooth = False  # nor the velocity smoother of issue 40

    def _turn_to_path(self, pose: tuple[float, float, float], points: np.ndarray,
                      margin: float) -> VelocityCommand | None:
        self._align_first = False
        return None
