"""A navigator with a planning defect, for the gap stressor's test: the reference navigator
planning and checking its motions as a point (a 4 cm footprint) with no extra cost near
obstacles — a footprint and an inflation layer left out of its configuration.

It lives in the tests because REI ships no broken navigator; runs import it as
``tests.rooms.no_inflation:NoInflationPlanner`` with the checkout on PYTHONPATH.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from rei.runtime.robot.gridplan import GridGraph
from rei.runtime.robot.protocol import ControllerContext
from rei.runtime.robot.reference import COMFORT, ReferenceNavigator

POINT = 0.04
"""m: the side of the footprint it believes it has."""


class NoInflationPlanner(ReferenceNavigator):
    """Plans and drives as if it were a point: every free cell costs the same, and a passage
    wider than a few centimetres is wide enough."""

    name = "no-inflation"

    def reset(self, context: ControllerContext) -> None:
        super().reset(replace(context, robot_size=(POINT, POINT)))

    def _grid_graph(self, inflate: float) -> GridGraph:
        clear = self._clear
        self._clear = np.where(clear > inflate, COMFORT + 1.0, clear)
        try:
            return super()._grid_graph(inflate)
        finally:
            self._clear = clear
