"""When a trajectory reaches each vertex, and whether the animator can walk it (TRAJ-SPEED).

``rei.lang.room.spline.vertex_times`` is the one place that turns a trajectory as written
(vertex times, or a ``total`` time shared out by length, and a loop's way back) into timed
control points: the generators write exactly these, and this check judges exactly these, so
what `rei-gen check` accepts is what the animator is given. A body must not have to move faster
than MAX_BODY_SPEED, nor reach a vertex sooner than MIN_SEGMENT_TIME after the one before
(generated files keep times to the microsecond: closer vertices would share a time, which
no spline can pass through). This module must never import the generators or the runtime.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from itertools import pairwise

from rei.lang.errors import Diagnostic
from rei.lang.room.model import Room, Vertex
from rei.lang.room.spline import vertex_times

MAX_BODY_SPEED = 10.0
"""m/s along the straight way between two vertices: a sprinter, seven times a walker
(WALKING_SPEEDS); beyond it the animator would throw bodies through the robot."""
MIN_SEGMENT_TIME = 0.01
"""s between two consecutive vertices: one physics step at the default 100 Hz."""


def walkable(times: Sequence[float], points: Sequence[tuple[float, float]]) -> bool:
    """Whether the animator can walk these timed control points: each segment takes at least
    MIN_SEGMENT_TIME and asks at most MAX_BODY_SPEED (what TRAJ-SPEED reports otherwise).
    Checks that sample the spline skip a trajectory that is not: its curve is not defined
    to any useful precision (a nanosecond segment swings it kilometres wide)."""
    return all(t1 - t0 >= MIN_SEGMENT_TIME and math.dist(p0, p1) / (t1 - t0) <= MAX_BODY_SPEED
               for (t0, t1), (p0, p1) in zip(pairwise(times), pairwise(points), strict=True))


def vertex_point(vertex: Vertex, cells: Mapping[str, tuple[int, int]], tile: float
                 ) -> tuple[float, float]:
    """Where a trajectory vertex is (metres): its floor's centre moved by its offset."""
    i, j = cells[vertex.floor.name]
    return i * tile + vertex.offset[0], j * tile + vertex.offset[1]


def check_motion(room: Room, cells: Mapping[str, tuple[int, int]]) -> list[Diagnostic]:
    """TRAJ-SPEED for every trajectory whose vertices all have a cell (others are reported
    by the rules that place them)."""
    out: list[Diagnostic] = []
    tile = room.tile_size
    for obj in room.objects:
        traj = obj.trajectory
        if traj is None or len(traj.vertices) < 2:
            continue
        if any(v.floor.name not in cells for v in traj.vertices):
            continue
        timed = [v.time is not None for v in traj.vertices]
        if (traj.total_time is None) != all(timed) or (traj.total_time is not None
                                                       and any(timed)):
            continue  # TRAJ-TIMES says what is missing
        written = traj.vertices
        if traj.total_time is None and any(b.time <= a.time for a, b in pairwise(written)
                                           if a.time is not None and b.time is not None):
            continue  # TRAJ-TIMES: times must increase
        points = [vertex_point(v, cells, tile) for v in written]
        times, pts = vertex_times(points, [v.time for v in written], traj.total_time,
                                  traj.loop)
        for i, ((t0, t1), (p0, p1)) in enumerate(zip(pairwise(times), pairwise(pts),
                                                     strict=True)):
            span = written[i + 1].span if i + 1 < len(written) else traj.span
            what = (f"'{obj.name}' from vertex {i + 1} to "
                    + (f"vertex {i + 2}" if i + 1 < len(written) else "its first vertex"))
            took, way = t1 - t0, math.dist(p0, p1)
            if took < MIN_SEGMENT_TIME:
                hint = ("; with a 'total' time a vertex on the floor of the one before takes "
                        "no time, give vertex times instead" if traj.total_time is not None
                        and way == 0.0 else "")
                out.append(Diagnostic(span, "TRAJ-SPEED",
                                      f"trajectory of {what}: expected at least "
                                      f"{MIN_SEGMENT_TIME:g} s, found {took:.3g} s{hint}"))
            elif way / took > MAX_BODY_SPEED:
                out.append(Diagnostic(span, "TRAJ-SPEED",
                                      f"trajectory of {what}: expected at most "
                                      f"{MAX_BODY_SPEED:g} m/s, found {way / took:.3g} m/s "
                                      f"({way:g} m in {took:.3g} s)"))
    return out
