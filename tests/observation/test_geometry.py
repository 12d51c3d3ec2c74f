"""Footprint distances: the vectorised geometry against a scalar reference, on random
oriented boxes, circles and polygons (exact, not centre to centre)."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rei.catalogue import Box, Cylinder, Polygon
from rei.runtime.observation.model.geometry import FootprintSet, local_shape


def _seg_point(p: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
    ax, ay = a
    bx, by = b
    px, py = p
    dx, dy = bx - ax, by - ay
    length2 = dx * dx + dy * dy
    t = 0.0 if length2 == 0 else max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / length2))
    return math.hypot(px - ax - t * dx, py - ay - t * dy)


def _segments_cross(a: tuple[float, float], b: tuple[float, float], c: tuple[float, float],
                    d: tuple[float, float]) -> bool:
    def orient(p: tuple[float, float], q: tuple[float, float], r: tuple[float, float]) -> float:
        return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
    return (orient(a, b, c) * orient(a, b, d) < 0) and (orient(c, d, a) * orient(c, d, b) < 0)


def _inside(p: tuple[float, float], poly: list[tuple[float, float]]) -> bool:
    inside = False
    for (x1, y1), (x2, y2) in zip(poly, poly[1:] + poly[:1], strict=False):
        if (y1 > p[1]) != (y2 > p[1]) and p[0] < x1 + (p[1] - y1) * (x2 - x1) / (y2 - y1):
            inside = not inside
    return inside


def _place(points: np.ndarray, pose: tuple[float, float, float]) -> list[tuple[float, float]]:
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return [(c * x - s * y + pose[0], s * x + c * y + pose[1]) for x, y in points]


def reference(robot: list[tuple[float, float]], other: list[tuple[float, float]] | None,
              centre: tuple[float, float], radius: float) -> float:
    """Plain-Python signed footprint distance (negative: depth of the deepest vertex)."""
    redges = list(zip(robot, robot[1:] + robot[:1], strict=False))
    if other is None:
        boundary = min(_seg_point(centre, a, b) for a, b in redges)
        return -boundary - radius if _inside(centre, robot) else boundary - radius
    oedges = list(zip(other, other[1:] + other[:1], strict=False))
    v1 = [min(_seg_point(p, a, b) for a, b in redges) for p in other]
    v2 = [min(_seg_point(p, a, b) for a, b in oedges) for p in robot]
    inside1 = [_inside(p, robot) for p in other]
    inside2 = [_inside(p, other) for p in robot]
    overlap = any(_segments_cross(a, b, c, d) for a, b in redges for c, d in oedges) or \
        any(inside1) or any(inside2)
    if not overlap:
        return min(v1 + v2)
    # the deepest vertex of either polygon inside the other (0 if only edges cross)
    return -max([v for v, i in zip(v1, inside1, strict=True) if i]
                + [v for v, i in zip(v2, inside2, strict=True) if i]
                + [0.0])


coord = st.floats(-3, 3, allow_nan=False)
angle = st.floats(-math.pi, math.pi, allow_nan=False)
size = st.floats(0.05, 1.5, allow_nan=False)


@settings(max_examples=200, deadline=None)
@given(robot_pose=st.tuples(coord, coord, angle), sizes=st.tuples(size, size),
       shapes=st.lists(st.tuples(st.sampled_from(["box", "circle", "poly"]), size, size,
                                 st.tuples(coord, coord, angle)), min_size=1, max_size=6))
def test_vectorised_distances_match_the_scalar_reference(
        robot_pose: tuple[float, float, float], sizes: tuple[float, float],
        shapes: list[tuple[str, float, float, tuple[float, float, float]]]) -> None:
    robot_fp = Box(*sizes)
    footprints = []
    for kind, a, b, _ in shapes:
        if kind == "box":
            footprints.append(Box(a, b))
        elif kind == "circle":
            footprints.append(Cylinder(a / 2))
        else:  # a convex pentagon
            footprints.append(Polygon(tuple((a * math.cos(k * 2 * math.pi / 5),
                                             b * math.sin(k * 2 * math.pi / 5))
                                            for k in range(5))))
    fs = FootprintSet.build(robot_fp, footprints, 1.0)
    assert (fs.poly_half is not None) == all(k != "poly" for k, *_ in shapes)
    poses = np.array([p for *_, p in shapes])
    got = fs.distances(robot_pose, poses)
    robot_local, _ = local_shape(robot_fp, 1.0)
    assert robot_local is not None
    robot = _place(robot_local, robot_pose)
    for i, fp in enumerate(footprints):
        local, radius = local_shape(fp, 1.0)
        other = None if local is None else _place(local, tuple(poses[i]))
        expected = reference(robot, other, (poses[i][0], poses[i][1]), radius)
        assert math.isclose(got[i], expected, abs_tol=1e-9), (i, fp, got[i], expected)


@settings(max_examples=200, deadline=None)
@given(robot_pose=st.tuples(coord, coord, angle), sizes=st.tuples(size, size),
       shapes=st.lists(st.tuples(st.sampled_from(["box", "circle"]), size, size,
                                 st.tuples(coord, coord, angle)), min_size=1, max_size=6))
def test_box_fast_path_matches_the_scalar_reference(
        robot_pose: tuple[float, float, float], sizes: tuple[float, float],
        shapes: list[tuple[str, float, float, tuple[float, float, float]]]) -> None:
    test_vectorised_distances_match_the_scalar_reference.hypothesis.inner_test(  # type: ignore[attr-defined]
        robot_pose, sizes, shapes)


def test_known_distances() -> None:
    fs = FootprintSet.build(Box(0.3, 0.2), [Box(1, 1), Cylinder(0.25)], 1.0)
    poses = np.array([[2.0, 0.0, 0.0], [0.0, 2.0, 0.0]])
    assert np.allclose(fs.distances((0, 0, 0), poses), [2 - 0.5 - 0.15, 2 - 0.25 - 0.1])
    assert np.allclose(fs.distances((0, 0, math.pi / 2), poses), [2 - 0.5 - 0.1, 2 - 0.25 - 0.15])
    # a box corner-first: exact distance is to the rotated corner, not the centre
    diamond = np.array([[2.0, 0.0, math.pi / 4], [0.0, 5.0, 0.0]])
    assert math.isclose(fs.distances((0, 0, 0), diamond)[0], 2 - math.sqrt(0.5) - 0.15)


def test_broad_phase_only_lowers_far_distances() -> None:
    fs = FootprintSet.build(Box(0.3, 0.2), [Box(1, 1)] * 3, 1.0)
    poses = np.array([[0.9, 0.0, 0.3], [5.0, 1.0, 0.0], [-20.0, 0.0, 0.0]])
    exact = fs.distances((0, 0, 0.1), poses)
    cut = fs.distances((0, 0, 0.1), poses, cutoff=0.5)
    assert cut[0] == exact[0]
    assert np.all(cut[1:] <= exact[1:]) and np.all(cut[1:] > 0.5)


def test_overlap_is_zero_or_negative() -> None:
    fs = FootprintSet.build(Box(0.3, 0.2), [Box(1, 1), Cylinder(0.2)], 1.0)
    d = fs.distances((0, 0, 0), np.array([[0.3, 0.0, 0.2], [0.05, 0.0, 0.0]]))
    assert np.all(d <= 0)


@settings(max_examples=300, deadline=None)
@given(robot_pose=st.tuples(coord, coord, angle), sizes=st.tuples(size, size),
       shapes=st.lists(st.tuples(st.sampled_from(["box", "circle"]), size, size,
                                 st.tuples(coord, coord, angle)), min_size=1, max_size=6),
       touching=st.booleans())
def test_scalar_narrow_phase_gives_the_same_bits_as_the_vectorised_one(
        robot_pose: tuple[float, float, float], sizes: tuple[float, float],
        shapes: list[tuple[str, float, float, tuple[float, float, float]]],
        touching: bool) -> None:
    """A few near objects take the Python-float narrow phase, many the numpy one: every
    distance must be identical to the last bit (outputs are compared byte for byte)."""
    footprints = [Box(a, b) if kind == "box" else Cylinder(a / 2) for kind, a, b, _ in shapes]
    poses = np.array([p for *_, p in shapes])
    if touching:  # objects on top of the robot: overlaps, depths, shared corners
        poses[:, :2] = np.array(robot_pose[:2]) + poses[:, :2] / 10
    fs = FootprintSet.build(Box(*sizes), footprints, 1.0)
    scalar = fs.distances(robot_pose, poses)
    vectorised = FootprintSet.build(Box(*sizes), footprints, 1.0)
    wanted = np.ones(len(footprints), dtype=bool)
    many = vectorised.refine(np.zeros(len(footprints)), wanted, robot_pose, poses,
                             scalar_limit=0)
    assert scalar.tobytes() == many.tobytes()


def test_boxes_kept_between_samples_follow_their_moves() -> None:
    """The scalar narrow phase keeps a box's corners while it stands still: a box that
    moves (or turns by a signed zero) is placed again, to the same bits as afresh."""
    footprints: list[Box | Cylinder] = [Box(1.0, 0.5), Box(0.4, 0.4), Cylinder(0.2)]
    kept = FootprintSet.build(Box(0.3, 0.2), footprints, 1.0)
    moves = [[[0.5, 0.0, 0.3], [0.0, 0.45, 0.0], [-0.4, 0.0, 0.0]],
             [[0.5, 0.0, 0.3], [0.0, 0.45, -0.0], [-0.35, 0.0, 0.0]],
             [[0.55, 0.05, 0.31], [0.0, 0.45, -0.0], [-0.35, 0.0, 0.0]],
             [[0.5, 0.0, 0.3], [0.1, 0.3, 1.0], [-0.3, 0.1, 0.0]]]
    for k, rows in enumerate(moves):
        poses = np.array(rows)
        robot = (0.01 * k, -0.02 * k, 0.1 * k)
        fresh = FootprintSet.build(Box(0.3, 0.2), footprints, 1.0)
        many = fresh.refine(np.zeros(3), np.ones(3, dtype=bool), robot, poses, scalar_limit=0)
        assert kept.distances(robot, poses).tobytes() == many.tobytes()
