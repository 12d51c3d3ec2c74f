"""How well a navigation task was done: its path and time against the shortest collision-free
path, and how much the robot turned in place near its goal (thesis 2.4: goals reached "with
minimal manoeuvring and in the possible shortest time").

The shortest path runs from where the robot was when the task started to the goal's point,
over the room's floor tiles (the stream header's floor centres; walls are no floors, a tile
under a static object's centre is blocked), any angle, never through a blocked tile nor between
two blocked tiles that touch only at a corner: the geodesic distance of the success-weighted
path length (SPL) of the navigation literature, on the abstract environment the queries already
read. It is exact for that environment: straight where the goal is in sight, otherwise bending
only at the corners of blocked tiles (a visibility graph, searched with networkx). A task is
judged only when that path less the goal's tolerance is at least ``MIN_JUDGED`` long: nearer
goals give ratios of noise. This module must never import the simulator.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import networkx as nx
import numpy as np

from rei.runtime.messages import GoalFacts

MIN_JUDGED = 0.5
"""m: a task whose shortest path less its tolerance is shorter is not judged (ratios 0)."""
SPIN_RADIUS = 0.5
"""m beyond the goal's tolerance within which turning in place counts as near the goal."""
IN_PLACE = 0.05
"""m/s: the robot turns in place while its own speed is below this."""
_EPS = 1e-9
"""Tile units: how near a boundary a point counts as on it."""
EXACT_CORNERS = 100
"""Obstacle corners up to which the exact path is searched over all of them: its visibility
graph joins every pair of corners (~0.3 CPU s at 100, once per run; a generated medium room
has 10-40). In a room with more (the 200-object hall of bench/simulation.py has ~800
corners, its 2,000-object one ~8,000, where that graph would cost minutes to hours) a tile
path pulled taut (``FloorGraph._pulled``) bounds the task's path, and the exact search runs
over the corners within that bound's ellipse when they are at most this many; else the
bound stands in (longer than the shortest path by a few per cent on average: ratios judged
against it err on the robot's side)."""
_STEPS = ((1, 0, 1.0), (-1, 0, 1.0), (0, 1, 1.0), (0, -1, 1.0), (1, 1, math.sqrt(2.0)),
          (1, -1, math.sqrt(2.0)), (-1, 1, math.sqrt(2.0)), (-1, -1, math.sqrt(2.0)))


class FloorGraph:
    """Shortest collision-free paths between points over the floor tiles, in metres.

    ``grid[i, j]`` is the floor index of the tile whose centre is ``origin + (i, j) * tile``
    (-1: no floor), ``blocked[k]`` whether floor ``k`` carries a static object. Internally
    positions are in tile units with a border of non-floor around the grid, so the tile
    ``(i, j)`` is the open square ``(i, i + 1) x (j, j + 1)``.
    """

    def __init__(self, grid: np.ndarray, origin: np.ndarray, tile: float,
                 blocked: np.ndarray) -> None:
        floor = grid >= 0
        free = floor.copy()
        free[floor] = ~blocked[grid[floor]]
        self.floor, self.free = np.pad(floor, 1), np.pad(free, 1)
        self.origin = np.asarray(origin, dtype=float)
        self.tile = float(tile)
        # Tile corners by how many of their four tiles are free: three make a convex corner of
        # an obstacle (where shortest paths bend), two diagonal ones a pinch nothing passes.
        f = self.free.astype(np.int8)
        around = f[:-1, :-1] + f[1:, :-1] + f[:-1, 1:] + f[1:, 1:]
        diagonal = (f[:-1, :-1] == f[1:, 1:]) & (f[1:, :-1] == f[:-1, 1:])
        self.corners = np.argwhere(around == 3).astype(float) + 1.0
        self.pinches = np.argwhere((around == 2) & diagonal).astype(float) + 1.0
        self._graph: nx.Graph | None = None

    def _units(self, xy: tuple[float, float]) -> np.ndarray:
        units: np.ndarray = (np.asarray(xy, dtype=float) - self.origin) / self.tile + 1.5
        return units

    def _tile_of(self, u: np.ndarray) -> tuple[int, int] | None:
        i, j = (int(math.floor(v)) for v in u)
        if 0 <= i < self.free.shape[0] and 0 <= j < self.free.shape[1]:
            return i, j
        return None

    def _clear(self, p: np.ndarray, q: np.ndarray, ignore: frozenset[tuple[int, int]]) -> bool:
        """The segment p-q (tile units) enters no closed tile's inside and passes no pinch;
        the tiles in ``ignore`` (where the task starts) count as free."""
        lo = np.floor(np.minimum(p, q)).astype(int)
        hi = np.floor(np.maximum(p, q)).astype(int)
        lo = np.maximum(lo - 1, 0)
        hi = np.minimum(hi + 1, np.array(self.free.shape) - 1)
        cells = np.argwhere(~self.free[lo[0]:hi[0] + 1, lo[1]:hi[1] + 1]) + lo
        if ignore and len(cells):
            cells = cells[[(int(a), int(b)) not in ignore for a, b in cells]]
        d = q - p
        if len(cells):
            # Liang-Barsky: the part of the segment inside each closed square, [t0, t1].
            t0, t1 = np.zeros(len(cells)), np.ones(len(cells))
            inside = np.ones(len(cells), dtype=bool)
            for axis in (0, 1):
                a, b = cells[:, axis].astype(float), cells[:, axis] + 1.0
                if abs(d[axis]) < _EPS:
                    inside &= (p[axis] >= a - _EPS) & (p[axis] <= b + _EPS)
                    continue
                ta, tb = (a - p[axis]) / d[axis], (b - p[axis]) / d[axis]
                t0, t1 = np.maximum(t0, np.minimum(ta, tb)), np.minimum(t1, np.maximum(ta, tb))
            mid = p[None, :] + d[None, :] * ((t0 + t1) / 2)[:, None]
            touches = inside & (t1 - t0 > _EPS)
            # A part of the segment that enters the open square: its middle is strictly inside.
            if (touches & np.all((mid > cells + _EPS) & (mid < cells + 1 - _EPS), axis=1)).any():
                return False
            # A part along a square's edge: blocked when the square across it is blocked too
            # (the seam between two blocked tiles is no passage).
            side = np.where(np.abs(mid - cells) <= _EPS, -1, 0) + np.where(
                np.abs(mid - cells - 1) <= _EPS, 1, 0)
            across = cells + side
            ok = np.all((across >= 0) & (across < np.array(self.free.shape)), axis=1)
            seam = touches & (side != 0).any(axis=1)
            if (seam & ~ok).any():
                return False
            seam &= ok
            if seam.any() and not self.free[across[seam, 0], across[seam, 1]].all():
                return False
        if len(self.pinches):
            near = self.pinches[np.all((self.pinches >= lo) & (self.pinches <= hi + 1), axis=1)]
            if len(near):
                length2 = float(d @ d)
                t = np.clip((near - p) @ d / length2, 0.0, 1.0) if length2 > 0 else \
                    np.zeros(len(near))
                gap = np.hypot(*(p[None, :] + t[:, None] * d[None, :] - near).T)
                if (gap < _EPS).any():
                    return False
        return True

    def _visibility(self, corners: np.ndarray) -> nx.Graph:
        """The visibility graph of ``corners`` (tile units): an edge, weighted by its length,
        between each pair the straight segment joins clear of the obstacles."""
        graph = nx.Graph()
        graph.add_nodes_from(range(len(corners)))
        for a in range(len(corners)):
            for b in range(a + 1, len(corners)):
                if self._clear(corners[a], corners[b], frozenset()):
                    graph.add_edge(a, b, weight=float(np.hypot(*(corners[b] - corners[a]))))
        return graph

    def _corner_graph(self) -> nx.Graph:
        """The visibility graph of all the obstacles' convex corners (built once, on first
        use)."""
        if self._graph is None:
            self._graph = self._visibility(self.corners)
        return self._graph

    def distance(self, start: tuple[float, float], goal: tuple[float, float]) -> float:
        """Metres of the shortest collision-free path from ``start`` to ``goal`` (inf when
        either is off the floors or nothing connects them). The tiles the two points are in
        count as free, so a robot starting beside an object still has a path."""
        p, q = self._units(start), self._units(goal)
        if not (np.isfinite(p).all() and np.isfinite(q).all()):
            return math.inf
        tiles = [self._tile_of(p), self._tile_of(q)]
        if any(t is None for t in tiles):
            return math.inf
        ignore = frozenset(t for t in tiles if t is not None)
        if not all(self.floor[t] for t in ignore):
            return math.inf
        if self._clear(p, q, ignore):
            return float(np.hypot(*(q - p))) * self.tile
        if len(self.corners) <= EXACT_CORNERS:
            return self._through(self._corner_graph().copy(), self.corners, p, q,
                                 ignore) * self.tile
        # Many corners: a path pulled taut bounds the shortest one, and every point of the
        # shortest lies within the ellipse of that length round the two ends; when few
        # corners lie in it, the search over those alone is exact.
        bound = self._pulled(p, q, ignore)
        if not math.isfinite(bound):
            return math.inf
        near = self.corners[np.hypot(*(self.corners - p).T) + np.hypot(*(self.corners - q).T)
                            <= bound + _EPS]
        if len(near) > EXACT_CORNERS:
            return bound * self.tile
        return min(bound, self._through(self._visibility(near), near, p, q, ignore)) * self.tile

    def _through(self, graph: nx.Graph, corners: np.ndarray, p: np.ndarray, q: np.ndarray,
                 ignore: frozenset[tuple[int, int]]) -> float:
        """Tile units of the shortest path from ``p`` to ``q`` over ``graph``, the visibility
        graph of ``corners`` (changed: the two ends are joined to it)."""
        for name, point in (("start", p), ("goal", q)):
            graph.add_node(name)
            for k, corner in enumerate(corners):
                if self._clear(point, corner, ignore):
                    graph.add_edge(name, k, weight=float(np.hypot(*(corner - point))))
        try:
            return float(nx.dijkstra_path_length(graph, "start", "goal"))
        except nx.NetworkXNoPath:
            return math.inf

    def _pulled(self, p: np.ndarray, q: np.ndarray, ignore: frozenset[tuple[int, int]]
                ) -> float:
        """Tile units of a collision-free path from ``p`` to ``q``: the shortest path over
        tile centres (8-connected, a diagonal step only past two free tiles), pulled taut
        (each point joined to the farthest later one in sight). Never shorter than the exact
        path, so a ratio judged against it errs on the robot's side; in sight of each other,
        or where the tiles' path bends only once, the two are one. Its cost grows with the
        tiles, not with the square of the obstacles' corners."""
        start, goal = self._tile_of(p), self._tile_of(q)
        assert start is not None and goal is not None

        def free(cell: tuple[int, int]) -> bool:
            return cell in ignore or bool(self.free[cell])

        best = {start: 0.0}
        parent: dict[tuple[int, int], tuple[int, int]] = {}
        heap = [(0.0, start)]
        while heap:
            cost, cell = heapq.heappop(heap)
            if cell == goal:
                break
            if cost > best[cell]:
                continue
            i, j = cell
            for di, dj, w in _STEPS:
                nxt = (i + di, j + dj)
                if not free(nxt) or (di and dj and not (free((i + di, j))
                                                        and free((i, j + dj)))):
                    continue
                if cost + w < best.get(nxt, math.inf) - 1e-12:
                    best[nxt], parent[nxt] = cost + w, cell
                    heapq.heappush(heap, (cost + w, nxt))
        if goal not in best:
            return math.inf
        cells = [goal]
        while cells[-1] != start:
            cells.append(parent[cells[-1]])
        points = [p, *(np.asarray(c, dtype=float) + 0.5 for c in reversed(cells[1:-1])), q]
        length, at = 0.0, 0
        while at < len(points) - 1:
            far = at + 1  # the next point is always in sight (a step between free tiles)
            while far + 1 < len(points) and self._clear(points[at], points[far + 1], ignore):
                far += 1
            length += float(np.hypot(*(points[far] - points[at])))
            at = far
        return length


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
    """Metres of the shortest path from the task's start to the goal's point (inf: no path
    over the floors)."""
    path_ratio: float
    """Path driven / shortest."""
    time_ratio: float
    """Time taken / the shortest path at the allowed speed."""
    spin: float


def judge_task(task: TaskProgress, ended: float, shortest: float,
               speed_limit: float) -> TaskEfficiency:
    """The task's figures against ``shortest``, the path to the goal's point itself (as SPL
    measures it): a navigator may stop anywhere within the goal's tolerance, but what it was
    sent to is the goal, and a path to its edge would make every short task of a navigator
    that drives onto its goal look long (1 m less a 0.3 m tolerance read a straight drive to
    within 0.1 m as 1.29 times the shortest path; issue 22). The tolerance only decides which
    tasks are long enough to judge."""
    tolerance = task.goal.tolerance if task.goal is not None else 0.0
    if not (math.isfinite(shortest) and shortest - tolerance >= MIN_JUDGED):
        return TaskEfficiency(shortest, 0.0, 0.0, task.spin)
    fastest = shortest / speed_limit if math.isfinite(speed_limit) and speed_limit > 0 else 0.0
    return TaskEfficiency(shortest, task.travelled / shortest,
                          (ended - task.started) / fastest if fastest > 0 else 0.0, task.spin)
