"""Laser clearance (issue 6): beam edges of an off-centre laser in a box footprint, worked by
hand; beams that hit nothing do not count; the runtime model keeps the latest scan's value."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from rei.catalogue import Box, Cylinder, Polygon
from rei.runtime.messages import LaserScan, RobotBelief, Sample, StreamHeader
from rei.runtime.observation.model.laser_clearance import (
    BeamEdges,
    beam_angles,
    beam_edges,
    clearance,
)
from rei.runtime.observation.model.runtime_model import FAR_AWAY, RuntimeModel
from rei.runtime.observation.model.sample_checks import check_sample
from tests.observation.helpers import monitor
from tests.observation.streams import ROBOT, header, sample, wall

WAFFLE = Box(0.281, 0.306)
MOUNT = (-0.064, 0.0)


def test_box_edges_of_an_off_centre_mount_are_the_hand_computed_ones() -> None:
    # Half sizes 0.1405 (x) and 0.153 (y); the laser sits 0.064 behind the centre.
    angles = np.array([0.0, math.pi / 2, math.pi, -math.pi / 2, math.pi / 4, -3 * math.pi / 4])
    edges = beam_edges(WAFFLE, MOUNT, angles)
    assert edges[0] == pytest.approx(0.1405 + 0.064)   # forward: to the front face
    assert edges[1] == pytest.approx(0.153)            # left
    assert edges[2] == pytest.approx(0.1405 - 0.064)   # back: to the rear face
    assert edges[3] == pytest.approx(0.153)            # right
    # diagonal forward-left: the side (y = 0.153) comes first, at 0.153 / sin 45°
    assert edges[4] == pytest.approx(0.153 * math.sqrt(2))
    # diagonal back-right: the rear face (x = -0.1405) first, 0.0765 / cos 45° from the mount
    assert edges[5] == pytest.approx(0.0765 * math.sqrt(2))


def test_a_lateral_offset_and_other_footprints() -> None:
    left = beam_edges(WAFFLE, (0.0, 0.05), np.array([math.pi / 2, -math.pi / 2]))
    assert left == pytest.approx([0.103, 0.203])
    # a circle of radius 0.2 from 0.1 ahead of the centre: 0.1 forward, 0.3 back,
    # sqrt(0.2² - 0.1²) sideways
    circle = beam_edges(Cylinder(0.2), (0.1, 0.0), np.array([0.0, math.pi, math.pi / 2]))
    assert circle == pytest.approx([0.1, 0.3, math.sqrt(0.03)])
    # a polygon that is the waffle's box gives the box's edges
    hx, hy = 0.1405, 0.153
    square = Polygon(((-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)))
    angles = np.linspace(-math.pi, math.pi, 37)
    assert beam_edges(square, MOUNT, angles) == pytest.approx(beam_edges(WAFFLE, MOUNT, angles))
    # a mount outside the footprint measures clearance from the mount: every edge is 0
    assert beam_edges(WAFFLE, (0.5, 0.0), angles).tolist() == [0.0] * 37


def _scan(ranges: list[float], angle_min: float = -math.pi) -> LaserScan:
    n = len(ranges)
    return LaserScan(angle_min, 2 * math.pi / n, 0.12, 3.5, np.array(ranges, dtype=float))


def test_clearance_is_the_smallest_range_minus_edge_over_the_beams_that_hit() -> None:
    scan = _scan([3.5, 0.5, 0.21, 0.9])  # back, right, forward, left
    assert beam_angles(scan) == pytest.approx([-math.pi, -math.pi / 2, 0.0, math.pi / 2])
    edges = beam_edges(WAFFLE, MOUNT, beam_angles(scan))
    # forward: 0.21 - 0.2045; the back beam saw nothing and would have given 3.5 - 0.0765
    assert clearance(scan, edges) == pytest.approx(0.21 - 0.2045)
    # nothing hit: max_range, as laser_min reads then
    assert clearance(_scan([3.5] * 4), edges) == 3.5
    # a laser_min that is at the back is smaller in range but farther from the footprint
    back = _scan([0.12, 3.5, 0.3, 3.5])
    assert min(back.ranges) == 0.12
    assert clearance(back, edges) == pytest.approx(0.12 - 0.0765)


def test_beam_edges_are_computed_once_per_scan_geometry() -> None:
    cache = BeamEdges(WAFFLE, MOUNT)
    first = cache.of(_scan([1.0] * 4))
    assert cache.of(_scan([2.0] * 4)) is first
    other = cache.of(_scan([1.0] * 8))
    assert len(other) == 8 and other is not first


def _wall_header() -> StreamHeader:
    w, _ = wall("wall_1", 2.0, 0.0)
    h = header([w])
    return StreamHeader(h.version, h.world, h.mission, h.seed, h.rate, ROBOT, h.objects,
                        h.tile_size, h.floors, MOUNT)


def _with_scan(seq: int, x: float, scan: LaserScan | None) -> Sample:
    """A sample of the robot at (x, 0) in front of the wall of ``_wall_header``."""
    s = sample(seq, seq / 10, (x, 0.0, 0.0), np.array([[2.0, 0.0, 0.0]]))
    b = s.belief
    laser_min = float(np.nanmin(scan.ranges)) if scan is not None else 3.5
    belief = RobotBelief(b.odom, b.odom_twist, laser_min, scan, b.nav_state, b.task)
    return Sample(s.seq, s.time, s.robot_pose, s.robot_twist, s.poses, s.twists, belief)


def _wall_scan(x: float) -> LaserScan:
    """A 4-beam scan of the robot at (x, 0) facing a wall whose face is at x = 1.5."""
    forward = 1.5 - (x + MOUNT[0])
    return _scan([3.5, 3.5, forward, 3.5])


def test_the_model_keeps_the_latest_scans_clearance_between_scans() -> None:
    model = RuntimeModel(_wall_header())
    assert model.baseline().laser_clearance == FAR_AWAY
    assert model.observe(_with_scan(0, 0.0, None)).laser_clearance == FAR_AWAY
    got = model.observe(_with_scan(1, 1.0, _wall_scan(1.0))).laser_clearance
    assert got == pytest.approx(1.5 - 1.0 - 0.1405)
    assert model.observe(_with_scan(2, 1.2, None)).laser_clearance == got  # no new scan


def test_a_drive_into_a_wall_with_an_off_centre_laser_raises_the_laser_signals(
        tmp_path: Path) -> None:
    # The footprint touches the wall face (x = 1.5) at x = 1.3595; laser_min is then 0.2045,
    # far above eps_collision, but the clearance reaches 0.
    xs = [0.8, 1.0, 1.2, 1.3, 1.36, 1.3, 1.2, 1.0, 0.8]
    samples = [_with_scan(i, x, _wall_scan(x)) for i, x in enumerate(xs)]
    rows, result = monitor(_wall_header(), samples, tmp_path)
    laser = [r.signal for r in rows if r.signal.startswith("SIG_LASER")]
    assert laser == ["SIG_LASER_CLOSE_TRANSIT_COLLISION", "SIG_LASER_COLLISION_TRANSIT_CLOSE"]
    verdicts = {v.requirement: v.status for v in result.verdicts}
    assert verdicts["GEOM_COLLISION_LASER_CORRECT"] == "pass"
    assert verdicts["GEOM_CLOSE_LASER_CORRECT"] == "pass"


def test_a_scan_with_non_finite_geometry_is_a_bad_sample_not_a_clearance() -> None:
    h = _wall_header()
    good = _with_scan(0, 1.0, _wall_scan(1.0))
    assert check_sample(good, h) is None
    nan_beam = _scan([float("nan"), 3.5, 0.5, float("inf")])  # beams without a return
    assert check_sample(_with_scan(1, 1.0, nan_beam), h) is None
    assert clearance(nan_beam, beam_edges(WAFFLE, MOUNT, beam_angles(nan_beam))) == \
        pytest.approx(0.5 - 0.2045)
    for bad in (LaserScan(math.nan, 1.0, 0.12, 3.5, np.ones(4)),
                LaserScan(-math.pi, 1.0, 0.12, math.inf, np.ones(4)),
                _scan([1.0, -math.inf, 1.0, 1.0])):
        assert check_sample(_with_scan(2, 1.0, bad), h) == "non_finite"
    flat = LaserScan(-math.pi, 1.0, 0.12, 3.5, np.ones((2, 2)))
    assert check_sample(_with_scan(3, 1.0, flat), h) == "malformed"
