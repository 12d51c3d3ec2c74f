"""Ray casting against the static map (runtime/robot/navigator/mapcast.py), checked against
a march."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rei.runtime.raycast import RayCaster, ShapeSet
from rei.runtime.robot.contract import MapObstacle
from rei.runtime.robot.navigator.mapcast import MapCaster

MAP = (
    MapObstacle("table", "static", 1.0, 0.5, 0.6, "box", 0.8, 0.6),
    MapObstacle("wall", "wall", -1.0, 0.0, 0.0, "box", 1.0, 1.0),
    MapObstacle("pillar", "static", 0.0, 1.5, 0.0, "cylinder", radius=0.2),
)


def _inside(x: float, y: float) -> bool:
    for o in MAP:
        dx, dy = x - o.x, y - o.y
        if o.shape == "cylinder":
            if math.hypot(dx, dy) <= o.radius:
                return True
            continue
        c, s = math.cos(o.yaw), math.sin(o.yaw)
        if abs(c * dx + s * dy) <= o.size_x / 2 and abs(-s * dx + c * dy) <= o.size_y / 2:
            return True
    return False


def _march(origin: tuple[float, float], angle: float, max_range: float) -> float:
    """The first millimetre step along the beam that is inside an obstacle (inf: none)."""
    for k in range(int(max_range / 1e-3) + 1):
        t = k * 1e-3
        if _inside(origin[0] + t * math.cos(angle), origin[1] + t * math.sin(angle)):
            return t
    return math.inf


@pytest.mark.parametrize("origin", [(0.0, 0.0), (0.3, 1.0), (-0.2, -0.7)])
def test_ranges_match_a_millimetre_march_for_boxes_and_cylinders(
        origin: tuple[float, float]) -> None:
    angles = np.linspace(-math.pi, math.pi, 72, endpoint=False)
    dirs = np.stack((np.cos(angles), np.sin(angles)), axis=1)
    got = MapCaster(MAP).ranges(origin, dirs, 2.5)
    want = np.array([_march(origin, float(a), 2.5) for a in angles])
    assert np.isfinite(want).sum() > 20  # the beams do hit the three shapes
    assert np.array_equal(np.isinf(got), np.isinf(want))
    finite = np.isfinite(want)
    assert np.allclose(got[finite], want[finite], atol=1.5e-3)


def test_a_beam_from_inside_an_obstacle_is_stopped_at_once_and_nothing_beyond_reach_counts(
        ) -> None:
    caster = MapCaster(MAP)
    east = np.array([[1.0, 0.0]])
    assert caster.ranges((1.0, 0.5), east, 2.0)[0] == 0.0  # inside the table
    assert caster.ranges((0.0, 1.5), east, 2.0)[0] == 0.0  # inside the pillar
    assert math.isinf(caster.ranges((-3.0, 0.0), east, 1.0)[0])  # the wall is 1.5 m away
    assert caster.ranges((-3.0, 0.0), east, 2.0)[0] == pytest.approx(1.5)


def test_a_beam_grazing_a_corner_hits_it_when_the_map_is_grown() -> None:
    """The table of tests/runtime/test_table_corner: the beam from the origin to its corner
    (0.02, 0.198) passed it by the rounding of its direction, and read the wall 0.3 m behind."""
    table = MapObstacle("table", "static", -0.19, 0.324, 0.0, "box", 0.42, 0.252)
    wall = MapObstacle("wall", "wall", 0.0, 1.0, 0.0, "box", 3.0, 1.0)
    corner = np.array([0.02, 0.198])
    beam = (corner / np.hypot(*corner))[None, :]
    grown = MapCaster((table, wall), grow=0.002).ranges((0.0, 0.0), beam, 3.0)[0]
    assert grown == pytest.approx(float(np.hypot(*corner)), abs=0.02)
    # The exact map misses the corner (the check above can fail).
    assert MapCaster((table, wall)).ranges((0.0, 0.0), beam, 3.0)[0] > 0.45


def test_a_shape_touched_at_exactly_the_reach_is_a_hit_at_the_reach() -> None:
    """The laser and the map caster share one cast (RayCaster): a shape whose nearest point
    is exactly at the reach is cast, and hit there — as the laser's own `t <= reach` counts
    a hit — whether it is a map's pillar or a body the laser sees."""
    pillar = MapObstacle("pillar", "static", 3.0, 0.0, 0.0, "cylinder", radius=1.0)
    east = np.array([[1.0, 0.0]])
    assert MapCaster((pillar,)).ranges((0.0, 0.0), east, 2.0)[0] == 2.0
    caster = RayCaster(ShapeSet(np.zeros((0, 5)), np.array([[3.0, 0.0, 1.0]])))
    assert caster.cast(np.zeros(2), east, 2.0)[0] == 2.0
    assert math.isinf(caster.cast(np.zeros(2), east, 1.999)[0])  # out of reach: left out
