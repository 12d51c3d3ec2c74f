"""The `reference` navigator's global planner: A* over a grid of free cells, without a graph
library.

The grid is the planning graph of ``ReferenceNavigator``: each free cell is a node, joined to
its eight neighbours when they are free, at a weight of the step's length times the mean of
the two cells' costs. ``GridGraph.astar`` is the same algorithm, step for step, as
``networkx.astar_path`` on the graph the navigator used to build with networkx (same
neighbour order, same heap tie-breaking by insertion count, same float sums), so it returns
the same path, while building the grid costs a few numpy operations instead of adding
hundreds of thousands of edges to a graph, and each expansion reads plain lists.
``tests/robot/test_gridplan.py`` checks the equivalence against networkx.
This module must never import pybullet.
"""

from __future__ import annotations

import math
from heapq import heappop, heappush

import numpy as np

DIRECTIONS = ((1, 0), (0, 1), (1, 1), (1, -1))
"""The forward steps joining a cell to its neighbours; each is walked both ways."""


class GridGraph:
    """The free cells of a grid and the weighted edges between neighbours (a per-run
    structure, read-only once built)."""

    def __init__(self, free: np.ndarray, cost: np.ndarray) -> None:
        nx_, ny_ = free.shape
        self.shape = (nx_, ny_)
        self.free_cells = np.argwhere(free)
        """(N, 2) indices of the free cells, in row-major order."""
        self._free: list[bool] = free.ravel().tolist()
        # For each direction d, the weight of the edge from cell u to u + d (flat index
        # u * ny + ...), None where there is none (u or u + d blocked or off the grid).
        self._weights: list[list[float | None]] = []
        self._offsets: list[int] = []
        for di, dj in DIRECTIONS:
            w = np.full((nx_, ny_), np.nan)
            i0, i1 = 0, nx_ - di
            j0, j1 = max(0, -dj), ny_ - max(0, dj)
            a = (slice(i0, i1), slice(j0, j1))
            b = (slice(i0 + di, i1 + di), slice(j0 + dj, j1 + dj))
            length = math.hypot(di, dj)
            both = free[a] & free[b]
            w[a] = np.where(both, length * 0.5 * (cost[a] + cost[b]), np.nan)
            flat = w.ravel().tolist()
            self._weights.append([None if v != v else v for v in flat])
            self._offsets.append(di * ny_ + dj)

    def __contains__(self, cell: tuple[int, int]) -> bool:
        i, j = cell
        return 0 <= i < self.shape[0] and 0 <= j < self.shape[1] and \
            bool(self._free[i * self.shape[1] + j])

    def weight(self, a: tuple[int, int], b: tuple[int, int]) -> float | None:
        """The weight of the edge between neighbouring cells ``a`` and ``b``; None when
        there is none."""
        if a not in self or b not in self:
            return None
        if b < a:
            a, b = b, a
        step = (b[0] - a[0], b[1] - a[1])
        if step not in DIRECTIONS:
            return None
        weights = self._weights[DIRECTIONS.index(step)]
        weight: float | None = weights[a[0] * self.shape[1] + a[1]]
        return weight

    def astar(self, source: tuple[int, int], target: tuple[int, int],
              blocked: set[tuple[int, int]] | None = None) -> list[tuple[int, int]] | None:
        """The cheapest path of cells from ``source`` to ``target`` (both free), avoiding the
        ``blocked`` cells other than those two; None when there is none. The heuristic is
        the straight-line distance in cells (admissible: every step costs at least its
        length)."""
        ny = self.shape[1]
        src = source[0] * ny + source[1]
        dst = target[0] * ny + target[1]
        ti, tj = target
        hidden = {i * ny + j for i, j in blocked if (i, j) != source and (i, j) != target} \
            if blocked else set()
        steps = list(zip(self._offsets, self._weights, strict=True))
        counter = 0
        queue: list[tuple[float, int, int, float, int]] = [(0.0, 0, src, 0.0, -1)]
        enqueued: dict[int, tuple[float, float]] = {}
        explored: dict[int, int] = {}
        hypot = math.hypot
        while queue:
            _, __, cur, dist, parent = heappop(queue)
            if cur == dst:
                path = [cur]
                node = parent
                while node != -1:
                    path.append(node)
                    node = explored[node]
                path.reverse()
                return [divmod(c, ny) for c in path]
            if cur in explored:
                if explored[cur] == -1:
                    continue
                if enqueued[cur][0] < dist:
                    continue
            explored[cur] = parent
            # The neighbour order of the networkx graph: per direction, the cell before, then
            # the cell after (the order its edges were added in).
            for off, weights in steps:
                for nb, cost in ((cur - off, weights[cur - off] if cur >= off else None),
                                 (cur + off, weights[cur])):
                    if cost is None or nb in hidden:
                        continue
                    ncost = dist + cost
                    seen = enqueued.get(nb)
                    if seen is not None:
                        if seen[0] <= ncost:
                            continue
                        h = seen[1]
                    else:
                        i, j = divmod(nb, ny)
                        h = hypot(i - ti, j - tj)
                    enqueued[nb] = ncost, h
                    counter += 1
                    heappush(queue, (ncost + h, counter, nb, ncost, cur))
        return None
