"""Plane geometry of generated rooms: spline sampling, clearance of a moving disc, paths.

Cells are integer (i, j) in the layout frame of rei.lang.room.layout (+i right, +j top); a
cell's centre is at (i, j) times the tile size. Humans walk a Catmull-Rom spline through
their control vertices (the thesis's animator, 6.2.3); we check the spline *and* the
straight control polygon, so a runtime that interpolates either way stays clear.
Pure functions only: no files, no random state.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Iterable, Iterator, Sequence

import networkx as nx
import numpy as np

Cell = tuple[int, int]

HUMAN_CLEARANCE = 0.35
"""Metres (in tiles of 1 m) a human's centre keeps from any blocked tile: its 0.25 m radius
plus a margin, so a neighbouring object that fills its tile up to the border is not touched."""

SAMPLE_STEP = 0.1


def catmull_rom(points: Sequence[tuple[float, float]], loop: bool,
                step: float = SAMPLE_STEP) -> np.ndarray:
    """Points along a uniform Catmull-Rom spline through ``points`` (closed when ``loop``),
    at most ``step`` apart along each chord (every segment gets the longest one's count)."""
    p = np.asarray(points, dtype=float)
    n = len(p)
    if n < 2:
        return p.copy()
    if loop:
        idx = np.arange(n)
        p0, p1, p2, p3 = p[(idx - 1) % n], p, p[(idx + 1) % n], p[(idx + 2) % n]
    else:
        ext = np.vstack([p[0], p, p[-1]])
        p0, p1, p2, p3 = ext[:-3], ext[1:-2], ext[2:-1], ext[3:]
    chord = np.hypot(*(p2 - p1).T).max()
    count = max(2, int(math.ceil(float(chord) / step)) + 1)
    t = np.linspace(0.0, 1.0, count)[:-1][None, :, None]
    p0, p1, p2, p3 = (q[:, None, :] for q in (p0, p1, p2, p3))
    seg = 0.5 * (2 * p1 + (p2 - p0) * t + (2 * p0 - 5 * p1 + 4 * p2 - p3) * t ** 2
                 + (-p0 + 3 * p1 - 3 * p2 + p3) * t ** 3)
    end = (p[0] if loop else p[-1])[None, :]
    return np.vstack([seg.reshape(-1, 2), end])


def polyline(points: Sequence[tuple[float, float]], loop: bool,
             step: float = SAMPLE_STEP) -> np.ndarray:
    """Points along the straight control polygon, at most ``step`` apart."""
    p = np.asarray(list(points) + ([points[0]] if loop else []), dtype=float)
    if len(p) < 2:
        return p
    a, b = p[:-1], p[1:]
    count = max(2, int(math.ceil(float(np.hypot(*(b - a).T).max()) / step)) + 1)
    t = np.linspace(0.0, 1.0, count)[:-1][None, :, None]
    seg = a[:, None, :] + (b - a)[:, None, :] * t
    return np.vstack([seg.reshape(-1, 2), p[-1:]])


class CellMask:
    """A set of unit cells as a boolean image, for vectorised look-ups (outside = False)."""

    def __init__(self, cells: Iterable[Cell]) -> None:
        cell_list = list(cells)
        if not cell_list:
            cell_list = [(0, 0)]
            empty = True
        else:
            empty = False
        ii = np.array([c[0] for c in cell_list])
        jj = np.array([c[1] for c in cell_list])
        self.i0, self.j0 = int(ii.min()), int(jj.min())
        self.mask = np.zeros((int(ii.max()) - self.i0 + 1, int(jj.max()) - self.j0 + 1),
                             dtype=bool)
        if not empty:
            self.mask[ii - self.i0, jj - self.j0] = True

    def contains(self, ci: np.ndarray, cj: np.ndarray) -> np.ndarray:
        a, b = ci - self.i0, cj - self.j0
        ok = (a >= 0) & (a < self.mask.shape[0]) & (b >= 0) & (b < self.mask.shape[1])
        out = np.zeros(ci.shape, dtype=bool)
        out[ok] = self.mask[a[ok], b[ok]]
        return out


_OFFSETS = np.array([(di, dj) for di in (-1, 0, 1) for dj in (-1, 0, 1)])


def _near_cells(samples: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """Unit cells (as two index arrays) within ``radius`` of some sample."""
    cells = np.floor(samples + 0.5).astype(int)[:, None, :] + _OFFSETS[None, :, :]
    gap = np.maximum(0.0, np.abs(samples[:, None, :] - cells) - 0.5)
    near = (gap ** 2).sum(axis=2) < radius * radius
    hits = cells[near]
    return hits[:, 0], hits[:, 1]


def disc_touches(samples: np.ndarray, blocked: CellMask,
                 radius: float = HUMAN_CLEARANCE) -> bool:
    """True when a disc of ``radius`` centred on any sample overlaps a blocked unit cell."""
    ci, cj = _near_cells(samples, radius)
    return bool(blocked.contains(ci, cj).any())


def swept_cells(samples: np.ndarray, radius: float = HUMAN_CLEARANCE) -> set[Cell]:
    """Unit cells a disc of ``radius`` moving through ``samples`` overlaps."""
    ci, cj = _near_cells(samples, radius)
    return set(zip(ci.tolist(), cj.tolist(), strict=False))


def path_graph(free: Iterable[Cell]) -> nx.Graph:
    """The inflated floor graph: free tiles, 4-neighbours, and diagonals whose two corner
    tiles are free too (the robot fits a tile, so it may cut a corner but not squeeze
    between two blocked tiles)."""
    free_set = set(free)
    graph: nx.Graph = nx.Graph()
    ordered = sorted(free_set)
    graph.add_nodes_from(ordered)
    diag = math.sqrt(2.0)
    edges: list[tuple[Cell, Cell, float]] = []
    for i, j in ordered:
        for di, dj in ((1, 0), (0, 1)):
            if (i + di, j + dj) in free_set:
                edges.append(((i, j), (i + di, j + dj), 1.0))
        for di, dj in ((1, 1), (1, -1)):
            other = (i + di, j + dj)
            if other in free_set and (i + di, j) in free_set and (i, j + dj) in free_set:
                edges.append(((i, j), other, diag))
    graph.add_weighted_edges_from(edges)
    return graph


def _octile(a: Cell, b: Cell) -> float:
    dx, dy = abs(a[0] - b[0]), abs(a[1] - b[1])
    return max(dx, dy) + (math.sqrt(2.0) - 1.0) * min(dx, dy)


def route(graph: nx.Graph, stops: Sequence[Cell]) -> list[Cell] | None:
    """Shortest path visiting ``stops`` in order on ``path_graph``, or None when a leg has
    no path (networkx A*; the reference for ``fast_route``)."""
    cells: list[Cell] = [stops[0]]
    for a, b in zip(stops[:-1], stops[1:], strict=True):
        if a == b:
            continue
        try:
            leg = nx.astar_path(graph, a, b, heuristic=_octile, weight="weight")
        except (nx.NetworkXNoPath, nx.NodeNotFound):
            return None
        cells.extend(leg[1:])
    return cells


_STEPS = ((1, 0, 1.0), (-1, 0, 1.0), (0, 1, 1.0), (0, -1, 1.0),
          (1, 1, math.sqrt(2.0)), (1, -1, math.sqrt(2.0)), (-1, 1, math.sqrt(2.0)),
          (-1, -1, math.sqrt(2.0)))


def fast_route(free: set[Cell], stops: Sequence[Cell]) -> list[Cell] | None:
    """The same search as ``route`` on the same graph (4-neighbours, and diagonals whose
    corner tiles are free), without building a networkx graph: building it costs more than
    the rest of a room's construction. Its lengths equal networkx's (tested); among equally
    short paths it may pick another."""
    cells: list[Cell] = [stops[0]]
    for a, b in zip(stops[:-1], stops[1:], strict=True):
        if a == b:
            continue
        if a not in free or b not in free:
            return None
        best = {a: 0.0}
        parent: dict[Cell, Cell] = {}
        heap = [(_octile(a, b), 0.0, a)]
        done: set[Cell] = set()
        bi, bj = b
        root2m1 = math.sqrt(2.0) - 1.0
        while heap:
            _, cost, cell = heapq.heappop(heap)
            if cell == b:
                break
            if cell in done:
                continue
            done.add(cell)
            i, j = cell
            for di, dj, w in _STEPS:
                nxt = (i + di, j + dj)
                if nxt not in free or nxt in done:
                    continue
                if di and dj and ((i + di, j) not in free or (i, j + dj) not in free):
                    continue
                new = cost + w
                if new < best.get(nxt, math.inf) - 1e-12:
                    best[nxt] = new
                    parent[nxt] = cell
                    dx, dy = abs(nxt[0] - bi), abs(nxt[1] - bj)  # octile distance, inlined
                    h = dx + root2m1 * dy if dx >= dy else dy + root2m1 * dx
                    heapq.heappush(heap, (new + h, new, nxt))
        if b not in parent:
            return None
        leg = [b]
        while leg[-1] != a:
            leg.append(parent[leg[-1]])
        cells.extend(reversed(leg[:-1]))
    return cells


def bfs_route(free: set[Cell], stops: Sequence[Cell]) -> list[Cell] | None:
    """A shortest 4-connected route through ``stops`` in order (a cheap first guess)."""
    cells: list[Cell] = [stops[0]]
    for a, b in zip(stops[:-1], stops[1:], strict=False):
        parent: dict[Cell, Cell | None] = {a: None}
        frontier = [a]
        while frontier and b not in parent:
            nxt = []
            for i, j in frontier:
                for n in ((i + 1, j), (i - 1, j), (i, j + 1), (i, j - 1)):
                    if n in free and n not in parent:
                        parent[n] = (i, j)
                        nxt.append(n)
            frontier = nxt
        if b not in parent:
            return None
        leg = [b]
        while parent[leg[-1]] is not None:
            leg.append(parent[leg[-1]])  # type: ignore[arg-type]
        cells.extend(reversed(leg[:-1]))
    return cells


def _flood(cells: set[Cell], start: Cell, barrier: Cell | None = None) -> Iterator[Cell]:
    """The cells of ``cells`` 4-connected to ``start`` (``start`` first), breadth first, never
    through ``barrier``; lazily, so a caller can stop as soon as it knows enough."""
    seen = {start} if barrier is None else {start, barrier}
    frontier = [start]
    yield start
    while frontier:
        nxt = []
        for i, j in frontier:
            for n in ((i + 1, j), (i - 1, j), (i, j + 1), (i, j - 1)):
                if n in cells and n not in seen:
                    seen.add(n)
                    nxt.append(n)
                    yield n
        frontier = nxt


def is_connected(cells: set[Cell]) -> bool:
    """Whether the 4-connected set ``cells`` is one piece (an empty set is)."""
    return not cells or sum(1 for _ in _flood(cells, min(cells))) == len(cells)


def stays_connected(free: set[Cell], cell: Cell) -> bool:
    """Whether removing ``cell`` from the 4-connected set ``free`` keeps its free neighbours
    connected to each other (so the whole free set stays one component)."""
    i, j = cell
    neighbours = [n for n in ((i + 1, j), (i - 1, j), (i, j + 1), (i, j - 1)) if n in free]
    if len(neighbours) <= 1:
        return True
    targets = set(neighbours[1:])
    for reached in _flood(free, neighbours[0], barrier=cell):
        targets.discard(reached)
        if not targets:
            return True
    return False


def entries(samples: np.ndarray, corridor: set[Cell], loop: bool) -> int:
    """How often a sampled trajectory enters the set of unit cells ``corridor``."""
    cells = np.floor(samples + 0.5).astype(int)
    inside = [(int(i), int(j)) in corridor for i, j in cells.tolist()]
    if not inside:
        return 0
    if all(inside):
        return 1
    count = sum(1 for prev, cur in zip(inside[:-1], inside[1:], strict=False) if cur and not prev)
    if inside[0] and (not loop or not inside[-1]):
        count += 1
    return count
