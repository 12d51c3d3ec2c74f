"""Shortest collision-free paths from a task's start to its goal, the yardstick of the
efficiency requirements (rei.runtime.observation.model.efficiency).

The shortest path runs from where the robot was when the task started to the goal's point: the
geodesic distance of the success-weighted path length (SPL) of the navigation literature. Two
estimates of it. ``FloorGraph``, the one judged with: over the stream header's floor tiles
(walls are no floors, a tile under a static object's centre blocked), any angle, never through
a blocked tile nor between two blocked tiles that touch only at a corner; exact for that
abstract environment (a visibility graph of the blocked tiles' corners, searched with
networkx). ``FreeSpace`` (issue 25; ``RuntimeModel.FOOTPRINT_PATHS``): through the robot's
real free space, the floors less every wall's and static object's footprint inflated by the
robot's inradius, bending only at the obstacles' convex vertices (an A* search; shapely for the
geometry); a lower bound of any route the robot can drive without touching anything, where the
tile estimate closes a small object's whole tile and keeps no distance from walls (errs both
ways by up to a third). This module must never import pybullet, the simulation, the evaluator
or the monitor's host.
"""

from __future__ import annotations

import heapq
import math

import networkx as nx
import numpy as np
import shapely

from rei.catalogue import Footprint
from rei.runtime.observation.model.geometry import local_shape

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
VERTICES_PER_CORNER = 2
"""An inflated footprint's corner is cut by one chord (two vertices): ``FreeSpace`` searches
over all its vertices up to this many per corner of ``EXACT_CORNERS``."""
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


class FreeSpace:
    """Shortest paths of the robot's reference point through the room's real free space, in
    metres: the floors less every wall and static object's footprint inflated by the robot's
    inradius about that point (``FootprintSet.robot_inradius``: the largest disc about the
    point inside the robot, so whatever way the robot faces, the point keeps that far from
    any obstacle). The free space it searches holds every place the point can be, so its
    shortest path is a lower bound of any route a robot drives without touching anything: a
    chair in a tile's centre no longer closes the tile, and a gap narrower than the robot's
    width is still closed. Inflated corners are cut by chords whose ends lie on the arc
    (shapely's buffer), which makes the obstacles a hair smaller (at most 0.3 of the
    inradius at a corner), never bigger. Paths bend only at the obstacles' convex vertices:
    an A* search over them, each vertex's sight lines tested when it is expanded (shapely,
    a prepared polygon). Past ``EXACT_CORNERS * VERTICES_PER_CORNER`` vertices (a hall of
    hundreds of objects) the search runs over the vertices within the ellipse of a bound
    round the two ends (the tile estimate, then the path found, which is exact once the
    path is no longer than the bound); where even that holds too many, the tile estimate
    (``FloorGraph``) stands in, as it does for a room whose header lists no wall or
    static object."""

    def __init__(self, tiles: FloorGraph, obstacles: list[shapely.Geometry],
                 clearance: float) -> None:
        """``obstacles``: the walls' and static objects' footprints already inflated by
        ``clearance``, the robot's inradius (``footprint_shapes``)."""
        self.tiles = tiles
        self.clearance = float(clearance)
        t = tiles.tile
        floor = np.argwhere(tiles.floor)  # padded grid: tile (i, j) has centre at i - 1
        centres = tiles.origin + (floor - 1.0) * t
        floors = shapely.union_all(shapely.box(centres[:, 0] - t / 2, centres[:, 1] - t / 2,
                                               centres[:, 0] + t / 2, centres[:, 1] + t / 2))
        lo = tiles.origin - 1.5 * t
        hi = tiles.origin + (np.array(tiles.floor.shape) - 1.5) * t
        self._frame = shapely.box(*lo, *hi)
        self.floors = floors
        # Off the floors is closed too, not inflated: nothing stands there to keep off.
        self.blocked = shapely.union_all([self._frame.difference(floors), *obstacles])
        self.free, self.vertices = self._prepare(self.blocked)

    def _prepare(self, blocked: shapely.Geometry) -> tuple[shapely.Geometry, np.ndarray]:
        """The free region (prepared) and its reflex vertices (the obstacles' convex ones:
        the only places a shortest path bends)."""
        free = shapely.orient_polygons(self._frame.difference(blocked))
        shapely.prepare(free)
        points: list[np.ndarray] = []
        for polygon in getattr(free, "geoms", [free]):
            if polygon.is_empty:
                continue
            for ring in (polygon.exterior, *polygon.interiors):
                xy = np.asarray(ring.coords)[:-1]
                if len(xy) < 3:
                    continue
                before, after = xy - np.roll(xy, 1, axis=0), np.roll(xy, -1, axis=0) - xy
                turn = before[:, 0] * after[:, 1] - before[:, 1] * after[:, 0]
                points.append(xy[turn < 0])  # a right turn with the free side on the left
        return free, np.concatenate(points) if points else np.zeros((0, 2))

    def _clear(self, free: shapely.Geometry, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Whether each segment a[k]-b[k] stays in ``free`` (its boundary included)."""
        lines = shapely.linestrings(np.stack((a, b), axis=1))
        return np.asarray(shapely.covers(free, lines), dtype=bool)

    def distance(self, start: tuple[float, float], goal: tuple[float, float]) -> float:
        """Metres of the shortest collision-free path of the robot's reference point from
        ``start`` to ``goal`` (inf when either is off the floors or nothing connects them).
        A disc of the inradius round each end counts as free, so a robot that starts beside
        an object, or a goal the robot can only reach within its tolerance, still has a
        path."""
        p, q = np.asarray(start, dtype=float), np.asarray(goal, dtype=float)
        if not (np.isfinite(p).all() and np.isfinite(q).all()):
            return math.inf
        ends = shapely.points([p, q])
        if not shapely.covers(self.floors, ends).all():
            return math.inf
        free, vertices = self.free, self.vertices
        if not shapely.covers(free, ends).all():
            discs = shapely.union_all(shapely.buffer(ends, self.clearance, quad_segs=2))
            free, vertices = self._prepare(self.blocked.difference(
                discs.intersection(self.floors)))
        if self._clear(free, p[None], q[None])[0]:
            return float(np.hypot(*(q - p)))
        if len(vertices) <= EXACT_CORNERS * VERTICES_PER_CORNER:
            return self._search(free, vertices, p, q)
        # Many vertices: any bound on the path keeps the search to the vertices within its
        # ellipse round the two ends; the path found there is exact once it is no longer
        # than the bound (the shortest path, no longer, lies wholly in the ellipse).
        tiles = bound = self.tiles.distance(start, goal)
        gap = np.hypot(*(vertices - p).T) + np.hypot(*(vertices - q).T)
        for _ in range(8):
            if not math.isfinite(bound):
                bound = 2.0 * float(np.hypot(*(q - p)))
            near = vertices[gap <= bound + _EPS]
            if len(near) > EXACT_CORNERS * VERTICES_PER_CORNER:
                break
            found = self._search(free, near, p, q)
            if found <= bound + _EPS:
                return found
            bound = found if math.isfinite(found) else 2.0 * bound
        return tiles

    def _search(self, free: shapely.Geometry, vertices: np.ndarray, p: np.ndarray,
                q: np.ndarray) -> float:
        """A* from ``p`` to ``q`` over ``vertices``, the sight lines of a vertex tested when
        it is expanded (the straight distance to ``q`` is the heuristic: consistent, so a
        vertex expanded is settled)."""
        nodes = np.concatenate((vertices, q[None]))
        goal = len(nodes) - 1
        h = np.hypot(*(nodes - q).T)
        best = np.full(len(nodes), math.inf)
        settled = np.zeros(len(nodes), dtype=bool)
        heap: list[tuple[float, float, int]] = []

        def expand(at: np.ndarray, cost: float) -> None:
            open_ = np.flatnonzero(~settled)
            length = np.hypot(*(nodes[open_] - at).T)
            better = cost + length < best[open_] - _EPS
            open_, length = open_[better], length[better]
            if not len(open_):
                return
            seen = self._clear(free, np.broadcast_to(at, (len(open_), 2)), nodes[open_])
            for k, d in zip(open_[seen].tolist(), length[seen].tolist(), strict=True):
                best[k] = cost + d
                heapq.heappush(heap, (cost + d + h[k], cost + d, k))

        expand(p, 0.0)
        while heap:
            _, cost, k = heapq.heappop(heap)
            if settled[k] or cost > best[k]:
                continue
            if k == goal:
                return cost
            settled[k] = True
            expand(nodes[k], cost)
        return math.inf


def footprint_shapes(footprints: list[Footprint], poses: np.ndarray, tile: float,
                     clearance: float = 0.0) -> list[shapely.Geometry]:
    """The footprints placed at ``poses`` ((N, 3): x, y, yaw) and inflated by ``clearance``,
    as shapely polygons whose vertices lie on the inflated outline (a hair smaller than it,
    never bigger): a polygon's corners rounded by one chord each, a circle an octagon."""
    shapes: list[shapely.Geometry] = []
    for fp, (x, y, yaw) in zip(footprints, np.asarray(poses, dtype=float), strict=True):
        local, radius = local_shape(fp, tile)
        if local is None:
            shapes.append(shapely.Point(x, y).buffer(radius + clearance, quad_segs=2))
            continue
        c, s = math.cos(yaw), math.sin(yaw)
        placed = shapely.Polygon(np.column_stack((c * local[:, 0] - s * local[:, 1] + x,
                                                  s * local[:, 0] + c * local[:, 1] + y)))
        shapes.append(placed.buffer(clearance, quad_segs=1) if clearance > 0 else placed)
    return shapes
