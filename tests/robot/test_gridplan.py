"""The navigator's grid A* returns the very path networkx's A* returned on the same graph.

The oracle is the graph the `reference` navigator built with networkx before
``rei.runtime.robot.navigator.gridplan`` replaced it (same nodes, edges, weights and insertion
order),
searched with ``networkx.astar_path`` and a view hiding the blocked cells; ties between equally
cheap paths must break the same way, or the navigator's runs would change.
"""

from __future__ import annotations

import math

import networkx as nx
import numpy as np
import pytest

from rei.runtime.robot.navigator.gridplan import GridGraph


def networkx_graph(free: np.ndarray, cost: np.ndarray) -> nx.Graph:
    nx_, ny_ = free.shape
    graph: nx.Graph = nx.Graph()
    idx = np.argwhere(free)
    graph.add_nodes_from(map(tuple, idx.tolist()))
    for di, dj in ((1, 0), (0, 1), (1, 1), (1, -1)):
        a, b = idx, idx + (di, dj)
        ok = (b[:, 0] < nx_) & (b[:, 1] >= 0) & (b[:, 1] < ny_)
        a, b = a[ok], b[ok]
        ok = free[b[:, 0], b[:, 1]]
        a, b = a[ok], b[ok]
        w = math.hypot(di, dj) * 0.5 * (cost[a[:, 0], a[:, 1]] + cost[b[:, 0], b[:, 1]])
        graph.add_weighted_edges_from(
            ((p0, p1), (q0, q1), c) for p0, p1, q0, q1, c in
            zip(a[:, 0].tolist(), a[:, 1].tolist(), b[:, 0].tolist(), b[:, 1].tolist(),
                w.tolist(), strict=True))
    return graph


def oracle(graph: nx.Graph, a: tuple[int, int], b: tuple[int, int],
           blocked: set[tuple[int, int]]) -> list[tuple[int, int]] | None:
    view = nx.restricted_view(graph, [c for c in blocked if c not in (a, b)], []) \
        if blocked else graph
    try:
        path: list[tuple[int, int]] = nx.astar_path(
            view, a, b, heuristic=lambda u, v: math.hypot(u[0] - v[0], u[1] - v[1]),
            weight="weight")
    except nx.NetworkXNoPath:
        return None
    return path


@pytest.mark.parametrize("seed", range(8))
def test_same_paths_as_networkx_on_random_grids(seed: int) -> None:
    rng = np.random.default_rng(seed)
    shape = (int(rng.integers(5, 40)), int(rng.integers(5, 40)))
    free = rng.random(shape) > 0.25
    # Uniform costs in large areas make many equally cheap paths: the tie-breaking matters.
    cost = np.where(rng.random(shape) < 0.5, 1.0, 1.0 + 4.0 * rng.random(shape))
    ours, theirs = GridGraph(free, cost), networkx_graph(free, cost)
    cells = [tuple(c) for c in np.argwhere(free).tolist()]
    assert sorted(ours.free_cells.tolist()) == sorted(list(c) for c in cells)
    for _ in range(25):
        a = cells[int(rng.integers(len(cells)))]
        b = cells[int(rng.integers(len(cells)))]
        blocked = {cells[int(k)] for k in rng.integers(len(cells), size=int(rng.integers(0, 30)))}
        assert ours.astar(a, b, blocked) == oracle(theirs, a, b, blocked)
        assert ours.astar(a, b) == oracle(theirs, a, b, set())


def test_membership_and_no_path() -> None:
    free = np.ones((6, 6), dtype=bool)
    free[:, 3] = False  # a wall across the grid
    graph = GridGraph(free, np.ones((6, 6)))
    assert (0, 0) in graph and (0, 3) not in graph and (6, 0) not in graph
    assert (-1, 0) not in graph
    assert graph.astar((0, 0), (5, 5)) is None
    assert graph.astar((0, 0), (0, 0)) == [(0, 0)]
    assert graph.astar((0, 0), (5, 0)) == [(i, 0) for i in range(6)]
    # A blocked cell on the way forces a detour; the start and goal are never blocked.
    detour = graph.astar((0, 0), (5, 0), {(2, 0), (0, 0), (5, 0)})
    assert detour is not None and (2, 0) not in detour
    assert (detour[0], detour[-1], len(detour)) == ((0, 0), (5, 0), 6)
    assert all(max(abs(p[0] - q[0]), abs(p[1] - q[1])) == 1
               for p, q in zip(detour, detour[1:], strict=False))


def test_edge_weights_are_networkx_weights() -> None:
    rng = np.random.default_rng(3)
    free = rng.random((9, 7)) > 0.2
    cost = 1.0 + 4.0 * rng.random((9, 7))
    ours, theirs = GridGraph(free, cost), networkx_graph(free, cost)
    for a in theirs.nodes:
        for b, data in theirs.adj[a].items():
            assert ours.weight(a, b) == data["weight"]
    assert ours.weight((0, 0), (2, 0)) is None  # not neighbours
