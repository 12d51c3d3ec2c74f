"""How well a navigation task was done: its path and time against the shortest collision-free
path, and how much the robot turned in place near its goal (thesis 2.4: goals reached "with
minimal manoeuvring and in the possible shortest time").

The shortest path runs over the room's floor tiles (the stream header's floor centres; walls
are no floors), 8-connected, a diagonal step only when both tiles beside it are free, a tile
under a static object's centre blocked: the success-weighted path length (SPL) of the
navigation literature, on the abstract environment the queries already read. Its tile-centre
steps make it a little longer than an any-angle path, so the ratios judged against it err on
the robot's side. A task is judged only when its shortest path (less the goal's tolerance) is
at least ``MIN_JUDGED`` long: nearer goals give ratios of noise. This module must never import
the simulator.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np

from rei.runtime.messages import GoalFacts

MIN_JUDGED = 0.5
"""m: a task whose shortest path (less its tolerance) is shorter is not judged (ratios 0)."""
SPIN_RADIUS = 0.5
"""m beyond the goal's tolerance within which turning in place counts as near the goal."""
IN_PLACE = 0.05
"""m/s: the robot turns in place while its own speed is below this."""


class FloorGraph:
    """Shortest paths between floor tiles (indices into the header's floors), in metres."""

    def __init__(self, cells: np.ndarray, grid: np.ndarray, centres: np.ndarray,
                 blocked: np.ndarray) -> None:
        self.cells, self.grid, self.centres, self.blocked = cells, grid, centres, blocked
        self._from: dict[int, dict[int, float]] = {}

    def _neighbours(self, k: int) -> list[tuple[int, float]]:
        i, j = (int(v) for v in self.cells[k])
        rows, cols = self.grid.shape

        def free(a: int, b: int) -> int:
            if 0 <= a < rows and 0 <= b < cols:
                other = int(self.grid[a, b])
                if other >= 0 and not self.blocked[other]:
                    return other
            return -1

        out = []
        for di in (-1, 0, 1):
            for dj in (-1, 0, 1):
                if di == dj == 0:
                    continue
                other = free(i + di, j + dj)
                if other < 0:
                    continue
                if di and dj and (free(i + di, j) < 0 or free(i, j + dj) < 0):
                    continue  # no corner cutting past a wall or an object
                out.append((other, float(np.hypot(*(self.centres[other] - self.centres[k])))))
        return out

    def distance(self, a: int, b: int) -> float:
        """Metres from floor ``a`` to floor ``b`` (inf when unconnected; Dijkstra, cached)."""
        if a < 0 or b < 0:
            return math.inf
        done = self._from.get(a)
        if done is None:
            done = {}
            queue = [(0.0, a)]
            while queue:
                d, k = heapq.heappop(queue)
                if k in done:
                    continue
                done[k] = d
                for other, step in self._neighbours(k):
                    if other not in done:
                        heapq.heappush(queue, (d + step, other))
            self._from[a] = done
        return done.get(b, math.inf)


@dataclass
class TaskProgress:
    """What the model gathers about the running task."""

    start_xy: tuple[float, float]
    started: float
    goal: GoalFacts | None
    travelled: float = 0.0
    spin: float = 0.0
    """Radians turned in place near the goal."""

    def observe(self, xy: tuple[float, float], step: float, own_speed: float,
                own_yaw_rate: float, dt: float) -> None:
        self.travelled += step
        goal = self.goal
        if goal is not None and own_speed < IN_PLACE and math.hypot(
                xy[0] - goal.x, xy[1] - goal.y) <= goal.tolerance + SPIN_RADIUS:
            self.spin += abs(own_yaw_rate) * dt


@dataclass(frozen=True)
class TaskEfficiency:
    """The judged figures of a task that succeeded (ratios 0: not judged)."""

    shortest: float
    """Metres of the shortest path less the goal's tolerance (inf: no path over the floors)."""
    path_ratio: float
    """Path driven / shortest."""
    time_ratio: float
    """Time taken / the shortest path at the allowed speed."""
    spin: float


def judge_task(task: TaskProgress, ended: float, shortest: float,
               speed_limit: float) -> TaskEfficiency:
    tolerance = task.goal.tolerance if task.goal is not None else 0.0
    length = shortest - tolerance
    if not (math.isfinite(length) and length >= MIN_JUDGED):
        return TaskEfficiency(length, 0.0, 0.0, task.spin)
    fastest = length / speed_limit if math.isfinite(speed_limit) and speed_limit > 0 else 0.0
    return TaskEfficiency(length, task.travelled / length,
                          (ended - task.started) / fastest if fastest > 0 else 0.0, task.spin)
