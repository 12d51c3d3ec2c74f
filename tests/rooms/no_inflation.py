"""A navigator with a planning defect, for the gap stressor's test: the reference navigator
planning and checking its motions as a point (a 4 cm footprint) with no extra cost near
obstacles — a footprint and an inflation layer left out of its configuration.

It lives in the tests because REI ships no broken navigator (bench/defects holds the
benchmark's); runs import it as ``tests.rooms.no_inflation:NoInflationPlanner`` with the
checkout on PYTHONPATH.
"""

from __future__ import annotations

from dataclasses import replace

from bench.defects.planning import FootprintTooSmall
from rei.runtime.robot.contract import ControllerContext
from rei.runtime.robot.navigator.reference import ReferenceNavigator

POINT = 0.04
"""m: the side of the footprint it believes it has."""


class NoInflationPlanner(FootprintTooSmall):
    """Plans and drives as if it were a point: every free cell costs the same (the planning
    graph of bench/defects' FootprintTooSmall), and a passage wider than a few centimetres
    is wide enough."""

    name = "no-inflation"

    def reset(self, context: ControllerContext) -> None:
        ReferenceNavigator.reset(self, replace(context, robot_size=(POINT, POINT)))
