"""Geometry of generated rooms: the route search agrees with networkx, splines, clearance."""

from __future__ import annotations

import math

import networkx as nx
from hypothesis import given, settings
from hypothesis import strategies as st

from rei.generators.rooms.geometry import (
    CellMask,
    catmull_rom,
    disc_touches,
    entries,
    fast_route,
    path_graph,
    route,
    stays_connected,
)


def _length(cells: list[tuple[int, int]]) -> float:
    return sum(math.dist(a, b) for a, b in zip(cells, cells[1:], strict=False))


@settings(max_examples=60, deadline=None)
@given(st.sets(st.tuples(st.integers(0, 7), st.integers(0, 5)), min_size=2, max_size=40),
       st.data())
def test_fast_route_is_as_short_as_networkx_astar(free: set[tuple[int, int]],
                                                  data: st.DataObject) -> None:
    ordered = sorted(free)
    stops = data.draw(st.lists(st.sampled_from(ordered), min_size=2, max_size=4))
    ours = fast_route(free, stops)
    theirs = route(path_graph(free), stops)
    assert (ours is None) == (theirs is None)
    if ours is not None and theirs is not None:
        assert math.isclose(_length(ours), _length(theirs))
        assert all(c in free for c in ours)
        graph = path_graph(free)
        assert all(graph.has_edge(a, b) for a, b in zip(ours, ours[1:], strict=False))


@settings(max_examples=60, deadline=None)
@given(st.sets(st.tuples(st.integers(0, 6), st.integers(0, 6)), min_size=3, max_size=40),
       st.data())
def test_stays_connected_agrees_with_networkx(free: set[tuple[int, int]],
                                              data: st.DataObject) -> None:
    graph = nx.grid_2d_graph(7, 7).subgraph(free)
    if not nx.is_connected(graph):
        return
    cell = data.draw(st.sampled_from(sorted(free)))
    rest = graph.subgraph(free - {cell})
    assert stays_connected(free, cell) == (len(rest) == 0 or nx.is_connected(rest))


def test_spline_passes_through_its_vertices_and_closes_a_loop() -> None:
    pts = [(0.0, 0.0), (4.0, 0.0), (4.0, 3.0)]
    open_curve = catmull_rom(pts, loop=False)
    closed = catmull_rom(pts, loop=True)
    for p in pts:
        assert min(math.dist(p, q) for q in open_curve.tolist()) < 1e-9
    assert closed[0].tolist() == closed[-1].tolist() == [0.0, 0.0]
    assert open_curve[-1].tolist() == [4.0, 3.0]


def test_clearance_and_entries() -> None:
    wall = CellMask({(2, 0)})
    near = catmull_rom([(0.0, 0.0), (1.0, 0.0)], loop=False)
    assert not disc_touches(near, wall, 0.45)
    assert disc_touches(near, wall, 0.55)
    across = catmull_rom([(0.0, -2.0), (0.0, 2.0)], loop=False)
    assert entries(across, {(0, 0)}, loop=False) == 1
    assert entries(catmull_rom([(0.0, -2.0), (0.0, 2.0), (3.0, 0.0)], loop=True),
                   {(0, 0)}, loop=True) >= 1
