"""Catmull-Rom (Hermite cubic) splines through timed control vertices (thesis 4.2.1, Table 1).

Per segment i, with h = t[i+1] - t[i]:
    a_i = (v[i+1] + v[i]) / h^2 - 2 (p[i+1] - p[i]) / h^3
    b_i = 3 (p[i+1] - p[i]) / h^2 - (v[i+1] + 2 v[i]) / h
    c_i = v[i],  d_i = p[i]
    r(t) = a_i (t - t_i)^3 + b_i (t - t_i)^2 + c_i (t - t_i) + d_i
and the vertex velocity is the mean of the two neighbouring chord velocities (thesis 4.2.1).
A loop wraps its neighbours around (its last vertex repeats the first); an open spline
starts and ends at rest. The room checks (TRAJ-CROSSES), the generators' picture and the
runtime's animator all walk this one curve. This module must never import the simulator.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from collections.abc import Sequence
from itertools import pairwise
from typing import cast

import numpy as np


class CatmullRom:
    def __init__(self, times: np.ndarray, points: np.ndarray, loop: bool) -> None:
        t = np.asarray(times, dtype=float)
        pts = np.asarray(points, dtype=float)
        if len(t) < 2 or np.any(np.diff(t) <= 0):
            raise ValueError("a spline needs at least two vertices at increasing times")
        self.t, self.p, self.loop = t, pts, loop
        n = len(t)
        chord = np.diff(pts, axis=0) / np.diff(t)[:, None]  # velocity along each segment
        v = np.zeros_like(pts)
        v[1:-1] = 0.5 * (chord[:-1] + chord[1:])
        if loop and n > 2:
            v[0] = v[-1] = 0.5 * (chord[-1] + chord[0])
        h = np.diff(t)[:, None]
        dp = pts[1:] - pts[:-1]
        self.a = (v[1:] + v[:-1]) / h**2 - 2 * dp / h**3
        self.b = 3 * dp / h**2 - (v[1:] + 2 * v[:-1]) / h
        self.c = v[:-1]
        self.d = pts[:-1]
        self.vertex_velocity = v
        # Evaluated once per body and physics step: plain floats beat numpy scalars there.
        self._times: list[float] = t.tolist()
        self._coef = [((float(a[0]), float(a[1])), (float(b[0]), float(b[1])),
                       (float(c[0]), float(c[1])), (float(d[0]), float(d[1])))
                      for a, b, c, d in zip(self.a, self.b, self.c, self.d, strict=False)]

    @property
    def duration(self) -> float:
        return self._times[-1] - self._times[0]

    def _local(self, time: float) -> tuple[int, float, bool]:
        """Segment index, time into it, and whether the spline has ended (open splines)."""
        times = self._times
        rel = time - times[0]
        if self.loop:
            rel = rel % (times[-1] - times[0])
        elif rel >= times[-1] - times[0]:
            return len(times) - 2, times[-1] - times[-2], True
        tt = times[0] + max(rel, 0.0)
        i = min(max(bisect_right(times, tt) - 1, 0), len(times) - 2)
        return i, tt - times[i], False

    def position(self, time: float) -> tuple[float, float]:
        i, s, _ = self._local(time)
        (ax, ay), (bx, by), (cx, cy), (dx, dy) = self._coef[i]
        return (((ax * s + bx) * s + cx) * s + dx, ((ay * s + by) * s + cy) * s + dy)

    def positions(self, times: np.ndarray) -> np.ndarray:
        """(N, 2) positions at many times at once (the same curve as ``position``)."""
        t0, span = self.t[0], self.t[-1] - self.t[0]
        rel = times - t0
        rel = np.mod(rel, span) if self.loop else np.clip(rel, 0.0, span)
        tt = t0 + rel
        i = np.clip(np.searchsorted(self.t, tt, side="right") - 1, 0, len(self.t) - 2)
        s = (tt - self.t[i])[:, None]
        return cast(np.ndarray, ((self.a[i] * s + self.b[i]) * s + self.c[i]) * s + self.d[i])

    def velocity(self, time: float) -> tuple[float, float]:
        i, s, ended = self._local(time)
        if ended:
            return 0.0, 0.0
        (ax, ay), (bx, by), (cx, cy), _ = self._coef[i]
        return ((3 * ax * s + 2 * bx) * s + cx, (3 * ay * s + 2 * by) * s + cy)


def vertex_times(points: Sequence[tuple[float, float]], times: Sequence[float | None],
                 total_time: float | None, loop: bool
                 ) -> tuple[list[float], list[tuple[float, float]]]:
    """The times and points a trajectory's spline passes through (the concrete model's).

    With ``total_time`` the time is shared out along the control polygon by length; else each
    vertex carries its own time, and a loop walks back to its first vertex at the
    trajectory's mean speed, unless it already ends there (a zero-length closing segment
    would take no time, which no spline can pass through). A loop's points end with its
    first point again. The generators write exactly these times and the checker judges
    exactly these (TRAJ-SPEED, TRAJ-CROSSES), so what `rei-gen check` accepts is what the
    animator is given.
    """
    pts = list(points)
    if total_time is None:
        out = [float(t or 0.0) for t in times]
        if loop:
            length = sum(math.dist(a, b) for a, b in pairwise(pts))
            speed = length / (out[-1] - out[0]) if out[-1] > out[0] else 0.0
            back = math.dist(pts[-1], pts[0])
            if back > 0.0 or len(pts) < 3:
                out.append(out[-1] + (back / speed if speed > 0 else out[-1] - out[0]))
                pts.append(pts[0])
        return out, pts
    if loop and (math.dist(pts[-1], pts[0]) > 0.0 or len(pts) < 3):
        pts.append(pts[0])
    seg = [math.dist(a, b) for a, b in pairwise(pts)]
    total_len = sum(seg)
    out = [0.0]
    for s in seg:
        share = s / total_len if total_len > 0 else 1.0 / len(seg)
        out.append(out[-1] + share * total_time)
    return out, pts


def walked_path(spline: CatmullRom, step: float) -> tuple[np.ndarray, np.ndarray]:
    """Times and (N, 2) points along the whole curve, at most ``step`` apart, for checks and
    pictures: the very curve ``position`` walks."""
    pieces: list[np.ndarray] = []
    for i in range(len(spline.t) - 1):
        t0, t1 = float(spline.t[i]), float(spline.t[i + 1])
        # As a Bezier curve the segment has these control points; over s in [0, 1] its speed
        # is at most three times the longest control leg, so evenly spaced s are close enough.
        h = t1 - t0
        p0, p1 = spline.p[i], spline.p[i + 1]
        c0 = p0 + spline.vertex_velocity[i] * h / 3
        c1 = p1 - spline.vertex_velocity[i + 1] * h / 3
        leg = max(float(np.linalg.norm(c0 - p0)), float(np.linalg.norm(c1 - c0)),
                  float(np.linalg.norm(p1 - c1)))
        count = max(2, math.ceil(3 * leg / step) + 1)
        pieces.append(np.linspace(t0, t1, count)[:-1])
    times = np.concatenate([*pieces, spline.t[-1:]])
    return times, spline.positions(times)
