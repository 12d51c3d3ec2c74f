"""Planning defects: the navigator plans for a robot that is not the one it drives."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from rei.runtime.robot.gridplan import GridGraph
from rei.runtime.robot.protocol import ControllerContext
from rei.runtime.robot.reference import COMFORT, ReferenceNavigator

FOOTPRINT_SCALE = 0.5
"""FootprintTooSmall plans with the footprint scaled by this along both axes."""


class FootprintTooSmall(ReferenceNavigator):
    """Defect: plans and checks its motions with a footprint half the robot's size and no
    extra cost near obstacles (inflation radius no bigger than that footprint), so its
    shortest paths hug furniture and cut corners the real robot does not fit round.

    Imitates: a footprint / robot_radius and inflation radius copied from a smaller robot's
    configuration.

    Expected catcher: the collision requirements (MISSION_SIMPLE, MISSION_SEQUENCE_CYCLE,
    GEOM_COLLISION_LASER_CORRECT).
    """

    name = "footprint-too-small"

    def reset(self, context: ControllerContext) -> None:
        w, h = context.robot_size
        super().reset(replace(context, robot_size=(w * FOOTPRINT_SCALE, h * FOOTPRINT_SCALE)))

    def _grid_graph(self, inflate: float) -> GridGraph:
        # Every free cell costs as much as one far from obstacles: no inflation gradient.
        clear = self._clear
        self._clear = np.where(clear > inflate, COMFORT + 1.0, clear)
        try:
            return super()._grid_graph(inflate)
        finally:
            self._clear = clear
