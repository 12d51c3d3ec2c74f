"""When a trajectory reaches each vertex, and whether the animator can walk it (TRAJ-SPEED).

``vertex_times`` is the one place that turns a trajectory as written (vertex times, or a
``total`` time shared out by length, and a loop's way back) into timed control points: the
generators write exactly these, and the checker judges exactly these, so what
`rei-gen check` accepts is what the animator is given. A body must not have to move faster
than MAX_BODY_SPEED, nor reach a vertex sooner than MIN_SEGMENT_TIME after the one before
(generated files keep times to the microsecond: closer vertices would share a time, which
no spline can pass through). This module must never import the generators or the runtime.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from itertools import pairwise

from rei.lang.errors import Diagnostic
from rei.lang.room.model import Room, Trajectory

MAX_BODY_SPEED = 10.0
"""m/s along the straight way between two vertices: a sprinter, seven times a walker
(WALKING_SPEEDS); beyond it the animator would throw bodies through the robot."""
MIN_SEGMENT_TIME = 0.01
"""s between two consecutive vertices: one physics step at the default 100 Hz."""

Point = tuple[float, float]


def vertex_times(trajectory: Trajectory, points: Sequence[Point]
                 ) -> tuple[list[float], list[Point]]:
    """Times and points of a trajectory's control vertices (``points`` in metres, one per
    written vertex); a loop gains its way back to the first vertex, walked at the
    trajectory's mean speed, unless it already ends there."""
    pts = list(points)
    if trajectory.total_time is None:
        times = [float(v.time or 0.0) for v in trajectory.vertices]
        if trajectory.loop:
            length = sum(math.dist(a, b) for a, b in pairwise(pts))
            speed = length / (times[-1] - times[0]) if times[-1] > times[0] else 0.0
            back = math.dist(pts[-1], pts[0])
            if back > 0.0 or len(pts) < 3:
                times.append(times[-1] + (back / speed if speed > 0 else times[-1] - times[0]))
                pts.append(pts[0])
        return times, pts
    if trajectory.loop and (math.dist(pts[-1], pts[0]) > 0.0 or len(pts) < 3):
        pts.append(pts[0])
    seg = [math.dist(a, b) for a, b in pairwise(pts)]
    total_len = sum(seg)
    times = [0.0]
    for s in seg:
        share = s / total_len if total_len > 0 else 1.0 / len(seg)
        times.append(times[-1] + share * trajectory.total_time)
    return times, pts


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
        points = [(cells[v.floor.name][0] * tile, cells[v.floor.name][1] * tile)
                  for v in written]
        times, pts = vertex_times(traj, points)
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
