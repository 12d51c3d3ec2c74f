"""The animator's Catmull-Rom spline (thesis 4.2.1, Table 1) and its velocity drive."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rei.runtime.simulation.animator import Animated, Animator, CatmullRom


def test_spline_passes_through_every_vertex_at_its_time() -> None:
    t = np.array([0.0, 8.0, 20.0, 28.0, 40.0])
    p = np.array([[5.0, -1.0], [5.0, -3.0], [2.0, -3.0], [2.0, -1.0], [5.0, -1.0]])
    spline = CatmullRom(t, p, loop=True)
    for ti, pi in zip(t[:-1], p[:-1], strict=False):
        assert spline.position(float(ti)) == pytest.approx(tuple(pi), abs=1e-12)
    # A loop repeats: one period later it is at the same place.
    assert spline.position(45.0) == pytest.approx(spline.position(5.0), abs=1e-9)


def test_coefficients_are_the_thesis_table_1() -> None:
    t = np.array([0.0, 2.0, 5.0])
    p = np.array([[0.0, 0.0], [2.0, 1.0], [3.0, 4.0]])
    s = CatmullRom(t, p, loop=False)
    v = s.vertex_velocity
    # v_1 = 1/2 ((p1 - p0)/(t1 - t0) + (p2 - p1)/(t2 - t1))
    assert v[1] == pytest.approx(0.5 * ((p[1] - p[0]) / 2 + (p[2] - p[1]) / 3))
    h = 2.0
    assert s.a[0] == pytest.approx((v[1] + v[0]) / h**2 - 2 * (p[1] - p[0]) / h**3)
    assert s.b[0] == pytest.approx(3 * (p[1] - p[0]) / h**2 - (v[1] + 2 * v[0]) / h)
    # Open splines start and stop at rest and stay at their last vertex.
    assert s.velocity(0.0) == (0.0, 0.0)
    assert s.position(100.0) == pytest.approx((3.0, 4.0))
    assert s.velocity(100.0) == (0.0, 0.0)


def test_velocity_is_the_derivative_of_position() -> None:
    s = CatmullRom(np.array([0.0, 3.0, 7.0, 9.0]),
                   np.array([[0.0, 0.0], [1.0, 2.0], [4.0, 2.0], [0.0, 0.0]]), loop=True)
    for time in (0.5, 3.3, 6.9, 8.2, 11.0):
        h = 1e-6
        a, b = s.position(time - h), s.position(time + h)
        numeric = ((b[0] - a[0]) / (2 * h), (b[1] - a[1]) / (2 * h))
        assert s.velocity(time) == pytest.approx(numeric, abs=1e-5)


def test_animator_follows_the_curve_and_pulls_back_a_displaced_body() -> None:
    s = CatmullRom(np.array([0.0, 10.0]), np.array([[0.0, 0.0], [10.0, 0.0]]), loop=False)
    animator = Animator([Animated(7, s, face_motion=True)], physics_rate=100.0)
    step = 500  # t = 5 s
    on_path = s.position(5.0)
    animator.correct(step, [(on_path[0], on_path[1], 0.0)])
    [(body, vx, vy, wz)] = animator.commands(step)
    assert body == 7 and vx == pytest.approx(s.velocity(5.005)[0], rel=1e-3)
    assert vy == pytest.approx(0.0) and wz == pytest.approx(0.0)
    # Pushed 0.3 m to the side and turned, it walks back to the path and turns to face it.
    animator.correct(step, [(on_path[0], on_path[1] + 0.3, math.pi / 2)])
    [(_, _, vy, wz)] = animator.commands(step)
    assert vy < 0 and wz < 0
    # The displacements of consecutive steps add up to the curve exactly.
    total = sum(animator.commands(k)[0][1] for k in range(100, 200)) / 100.0
    assert total == pytest.approx(s.position(2.0)[0] - s.position(1.0)[0])


def test_spline_refuses_vertices_out_of_time_order() -> None:
    with pytest.raises(ValueError):
        CatmullRom(np.array([0.0, 0.0]), np.array([[0.0, 0.0], [1.0, 1.0]]), loop=False)


@pytest.mark.parametrize("loop", [True, False])
def test_vectorised_positions_equal_single_ones(loop: bool) -> None:
    s = CatmullRom(np.array([0.0, 3.0, 7.0, 9.0]),
                   np.array([[0.0, 0.0], [1.0, 2.0], [4.0, 2.0], [0.0, 0.0]]), loop=loop)
    times = np.linspace(-1.0, 25.0, 301)
    many = s.positions(times)
    for t, row in zip(times, many, strict=True):
        assert tuple(row) == pytest.approx(s.position(float(t)), abs=1e-12)
