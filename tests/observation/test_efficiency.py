"""Efficiency requirements (EFFICIENT_PATH, TIME_TO_GOAL, NO_SPIN_AT_GOAL): each task that
succeeded is judged against the shortest collision-free path over the floors — its path and
its time at the allowed speed — and by how much the robot turned in place near the goal.

The shortest path and the ratios are tested on their own; then, in the real simulator, the
reference navigator passes all three in an open room and three navigators each fail one: one
that takes a detour, one that crawls, one that oscillates in place before reporting success.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import networkx as nx
import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from rei.catalogue import Box, Cylinder, Footprint, Tile
from rei.runtime.messages import (
    SCHEMA_VERSION,
    GoalFacts,
    MissionEvent,
    MissionFacts,
    NavState,
    ObservedObject,
    RobotBelief,
    Sample,
    StreamHeader,
)
from rei.runtime.observation.model import free_space as efficiency
from rei.runtime.observation.model.efficiency import TaskProgress, judge_task
from rei.runtime.observation.model.floors import FloorMap
from rei.runtime.observation.model.free_space import FloorGraph, FreeSpace, footprint_shapes
from rei.runtime.observation.model.runtime_model import RuntimeModel
from tests.observation.helpers import monitor
from tests.observation.streams import ROBOT

REPO = Path(__file__).resolve().parents[2]


def _graph(rows: list[str], blocked: str = "") -> tuple[FloorGraph, dict[str, tuple[float, float]]]:
    """Floors of a character grid ('.' floor, '#' wall, letters: named floors; names in
    ``blocked`` carry a static object) and the centre of each named floor."""
    centres, names = [], {}
    for r, row in enumerate(rows):
        for c, ch in enumerate(row):
            if ch != "#":
                names[ch] = len(centres)
                centres.append((float(c), float(-r)))
    floors = FloorMap(np.array(centres, dtype=float).reshape(-1, 2), 1.0)  # (0, 2): no floor
    mask = np.zeros(len(centres), dtype=bool)
    for name in blocked:
        mask[names[name]] = True
    return (FloorGraph(floors.grid, floors.origin, floors.tile, mask),
            {name: centres[k] for name, k in names.items()})


def test_the_shortest_path_is_straight_in_sight_and_bends_only_at_corners() -> None:
    graph, n = _graph(["a.b",
                       ".#.",
                       "c.d"])
    assert graph.distance(n["a"], n["b"]) == pytest.approx(2.0)
    # round the wall by its corner (1.5, -0.5): two legs of sqrt(1.5² + 0.5²)
    assert graph.distance(n["a"], n["d"]) == pytest.approx(2 * math.hypot(1.5, 0.5))
    open_graph, m = _graph(["a..",
                            "...",
                            "..d"])
    assert open_graph.distance(m["a"], m["d"]) == pytest.approx(2 * math.sqrt(2))
    # from where the robot is, not from its tile's centre: 0.4 m off it, 0.4 m shorter
    assert open_graph.distance((0.4, 0.0), m["d"]) == pytest.approx(math.hypot(1.6, 2.0))
    u_turn, k = _graph(["a.....",
                        "#####.",
                        "b....."])
    # a U round the wall's end: both corners of the gap, never the seam between wall tiles
    assert u_turn.distance(k["a"], k["b"]) == pytest.approx(2 * math.hypot(4.5, 0.5) + 1.0)


def test_the_shortest_path_never_passes_objects_seams_or_pinches() -> None:
    blocked, k = _graph(["a.x.b"], blocked="x")
    assert blocked.distance(k["a"], k["b"]) == math.inf
    pinch, p = _graph(["a#",
                       "#b"])
    assert pinch.distance(p["a"], p["b"]) == math.inf  # tiles touching at a corner only
    diagonal, d = _graph(["a#..",
                          "..#b"])
    assert diagonal.distance(d["a"], d["b"]) == math.inf
    seam, _ = _graph(["...",
                      ".#.",
                      ".#.",
                      "..."])
    # along the seam between the two wall tiles would be 2 m; round the wall's end instead
    assert seam.distance((0.0, -1.5), (2.0, -1.5)) == pytest.approx(2 * math.hypot(0.5, 1.0) + 1)
    # an object's tile is blocked for paths past it, but a task starting on it is judged
    start_on, o = _graph(["x..b"], blocked="x")
    assert start_on.distance(o["x"], o["b"]) == pytest.approx(3.0)
    assert start_on.distance((-3.0, 0.0), o["b"]) == math.inf  # off the floors


@settings(max_examples=60, deadline=None)
@given(st.lists(st.text("..#x", min_size=5, max_size=5), min_size=4, max_size=4),
       st.integers(0, 19), st.integers(0, 19))
def test_the_shortest_path_lies_between_the_straight_line_and_the_tile_steps(
        rows: list[str], a: int, b: int) -> None:
    """The law of any room: no path is shorter than the straight line, the any-angle path is
    never longer than one over tile centres (8-connected, no corner cutting: networkx's own
    Dijkstra as the oracle), it is the same both ways, and it exists exactly when the tiles
    connect through shared edges."""
    objects = "".join(chr(ord("A") + k) for k in range(26))
    named, k = [], 0
    for row in rows:
        line = ""
        for ch in row:
            line += objects[k] if ch == "x" else ch
            k += ch == "x"
        named.append(line)
    graph, _ = _graph(named, blocked=objects[:k])
    free = {(c, -r) for r, row in enumerate(named) for c, ch in enumerate(row) if ch == "."}
    cells = sorted(free)
    assume(len(cells) > max(a, b))
    p, q = cells[a], cells[b]
    tiles = nx.Graph()
    tiles.add_nodes_from(cells)
    edges = nx.Graph()
    edges.add_nodes_from(cells)
    for x, y in cells:
        for dx, dy in ((1, 0), (0, 1), (1, 1), (1, -1)):
            o = (x + dx, y + dy)
            cut = dx and dy and ((x + dx, y) not in free or (x, y + dy) not in free)
            if o not in free or cut:
                continue
            tiles.add_edge((x, y), o, weight=math.hypot(dx, dy))
            if not (dx and dy):
                edges.add_edge((x, y), o)
    found = graph.distance(p, q)
    assert found == pytest.approx(graph.distance(q, p))
    assert math.isfinite(found) == nx.has_path(edges, p, q)
    if math.isfinite(found):
        assert found >= math.dist(p, q) - 1e-9
        assert found <= nx.dijkstra_path_length(tiles, p, q) + 1e-9


def _hall(cols: int, rows: int) -> FloorGraph:
    """A hall with an object on every second tile of every second row (bench/simulation.py's
    lattice): four corners per object."""
    grid = np.arange(cols * rows).reshape(cols, rows)
    blocked = np.zeros(cols * rows, dtype=bool)
    blocked[grid[1:-1:2, 1:-1:2].ravel()] = True
    return FloorGraph(grid, np.zeros(2), 1.0, blocked)


def test_a_room_of_many_corners_never_joins_every_pair_of_them(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The visibility graph of all corners grows with their square (~8,000 corners in the
    2,000-object hall): past EXACT_CORNERS it is never built. A short task is still exact
    (the corners within its bound's ellipse are few); a long one gets a path pulled taut,
    between the exact path and the tile path, never shorter than the exact one."""
    hall = _hall(20, 10)  # 144 corners (the 2,000-object hall of the benchmark: 7,936)
    assert len(hall.corners) > efficiency.EXACT_CORNERS
    short = hall.distance((10.0, 4.0), (4.0, 8.0))
    across = hall.distance((0.0, 0.0), (19.0, 9.0))
    assert hall._graph is None  # no graph of every pair was made
    monkeypatch.setattr(efficiency, "EXACT_CORNERS", 10_000)
    exact = _hall(20, 10)
    assert short == pytest.approx(exact.distance((10.0, 4.0), (4.0, 8.0)))
    assert math.hypot(19.0, 9.0) < exact.distance((0.0, 0.0), (19.0, 9.0)) <= across
    assert across <= 19.0 + 9.0  # no longer than the tile steps along the free rows


@settings(max_examples=40, deadline=None)
@given(st.lists(st.text("..x", min_size=6, max_size=6), min_size=6, max_size=6),
       st.integers(0, 35), st.integers(0, 35))
def test_the_bounded_search_is_never_shorter_than_the_exact_one(rows: list[str], a: int,
                                                                 b: int) -> None:
    """With the cap at 4 corners (most rooms here exceed it), every path found is one the
    exact search could take: at least the exact length, finite exactly when it is."""
    objects = "".join(chr(ord("A") + k) for k in range(26))
    named, k = [], 0
    for row in rows:
        line = ""
        for ch in row:
            line += objects[k % 26] if ch == "x" and k < 26 else ("." if ch == "x" else ch)
            k += ch == "x"
        named.append(line)
    graph, _ = _graph(named, blocked=objects[:min(k, 26)])
    cells = sorted((c, -r) for r, row in enumerate(named) for c, ch in enumerate(row)
                   if ch == ".")
    assume(len(cells) > max(a, b))
    p, q = cells[a], cells[b]
    exact = graph.distance(p, q)
    cap = efficiency.EXACT_CORNERS
    try:
        efficiency.EXACT_CORNERS = 4
        bounded = _graph(named, blocked=objects[:min(k, 26)])[0].distance(p, q)
    finally:
        efficiency.EXACT_CORNERS = cap
    assert math.isfinite(bounded) == math.isfinite(exact)
    if math.isfinite(exact):
        assert bounded >= exact - 1e-9


WAFFLE = 0.1405
"""m: the TurtleBot3 Waffle's inradius about its centre (half its 0.281 m width)."""


def _space(rows: list[str], objects: list[tuple[Footprint, tuple[float, float]]],
           clearance: float = WAFFLE) -> tuple[FloorGraph, FreeSpace]:
    """The tile estimate and the footprint one of a character grid ('#' a wall tile, as a
    generated room's header lists it; anything else floor, row r at y = -r) with static
    ``objects`` (footprint, centre) standing on it."""
    floors, walls = [], []
    for r, row in enumerate(rows):
        for c, ch in enumerate(row):
            (walls if ch == "#" else floors).append((float(c), float(-r)))
    grid = FloorMap(np.array(floors), 1.0)
    under = grid.of(np.array([xy for _, xy in objects], dtype=float).reshape(-1, 2))
    blocked = np.zeros(len(floors), dtype=bool)
    blocked[under[under >= 0]] = True
    tiles = FloorGraph(grid.grid, grid.origin, 1.0, blocked)
    footprints: list[Footprint] = [Tile()] * len(walls) + [fp for fp, _ in objects]
    poses = np.array([(x, y, 0.0) for x, y in walls] + [(x, y, 0.0) for _, (x, y) in objects])
    return tiles, FreeSpace(tiles, footprint_shapes(footprints, poses, 1.0, clearance),
                            clearance)


CHAIR_ROOM = ["#########",
        "#.......#",
        "#.......#",
        "#########"]


def test_a_chair_in_a_tiles_centre_leaves_the_straight_way_beside_it() -> None:
    """Issue 25: a 0.3 m chair at a tile's centre, a task 0.3 m to its side. The tile
    estimate closes the chair's whole tile and detours round it; the robot's real free space
    (the chair inflated by the robot's half width, 0.29 m from its centre) leaves the
    straight way, and the estimate is that straight distance. Through the chair it bends
    round the inflated chair: longer than straight, shorter than round the tile."""
    tiles, space = _space(CHAIR_ROOM, [(Box(0.3, 0.3), (4.0, -1.0))])
    beside = ((3.0, -1.3), (5.0, -1.3))
    assert space.distance(*beside) == pytest.approx(2.0)
    assert tiles.distance(*beside) == pytest.approx(2 * math.hypot(0.5, 0.2) + 1.0)
    through = ((1.0, -1.0), (7.0, -1.0))
    assert 6.0 + 0.01 < space.distance(*through) < tiles.distance(*through)
    # a pillar: its inflated circle, the octagon inscribed in it (never bigger)
    _, pillar = _space(CHAIR_ROOM, [(Cylinder(0.15), (4.0, -1.0))])
    assert pillar.distance((1.0, -1.3), (7.0, -1.3)) == pytest.approx(6.0)
    assert pillar.distance((1.0, -1.25), (7.0, -1.25)) > 6.0


@pytest.mark.parametrize(("size", "passes"), [(0.8, False), (0.62, True)])
def test_a_gap_narrower_than_the_robot_is_never_used(size: float, passes: bool) -> None:
    """Three boxes across a 3 m wide room, a tile apart: gaps of 0.2 m (narrower than the
    robot's 0.281 m width) leave no way through; gaps of 0.38 m do, straight."""
    rows = ["#####",
            "#...#",
            "#...#",
            "#...#",
            "#####"]
    boxes: list[tuple[Footprint, tuple[float, float]]] = [
        (Box(size, size), (2.0, -float(r))) for r in (1, 2, 3)]
    _, space = _space(rows, boxes)
    found = space.distance((1.0, -1.5), (3.0, -1.5))
    assert (found == pytest.approx(2.0)) if passes else found == math.inf
    # the same room and gaps for a robot a tenth as wide: the narrow gaps open
    _, thin = _space(rows, boxes, clearance=WAFFLE / 10)
    assert thin.distance((1.0, -1.5), (3.0, -1.5)) == pytest.approx(2.0)


def test_a_wall_keeps_the_robot_half_its_width_away() -> None:
    """Round a wall's end the path bends at the wall's corner inflated by the robot's
    inradius (cut by a chord: a hair shorter than the arc, never longer), and a goal within
    the inradius of a wall still has its path (a disc of the inradius round each end is
    free)."""
    rows = ["......",
            "#####.",
            "......"]
    tiles, space = _space(rows, [])
    a, b = (0.0, 0.0), (0.0, -2.0)
    found = space.distance(a, b)
    assert found > tiles.distance(a, b)  # the tiles let it graze the wall's corners
    # the exact path: tangent to the arc of the inradius round each corner of the wall's end,
    # round it, down the gap half a metre each side
    d = math.hypot(4.5, 0.5)
    turn = math.pi / 2 - math.atan2(0.5, 4.5) - math.asin(WAFFLE / d)
    arcs = 2 * (math.sqrt(d * d - WAFFLE * WAFFLE) + WAFFLE * turn + 0.5)
    assert arcs - 0.05 < found <= arcs + 1e-9
    assert math.isfinite(space.distance((0.0, -0.45), (3.0, -0.45)))


@settings(max_examples=60, deadline=None)
@given(st.lists(st.text("..#x", min_size=5, max_size=5), min_size=4, max_size=4),
       st.integers(0, 19), st.integers(0, 19))
def test_with_whole_tile_objects_and_no_width_the_two_estimates_agree(
        rows: list[str], a: int, b: int) -> None:
    """The law that ties the footprint estimate to the tile one (whose exactness is tested
    above): objects that fill their tiles and a robot of (almost) no width leave the same
    free space, so the two find paths of the same length (within the corners' chords) and
    find one exactly when the other does."""
    walls = ["".join("#" if ch == "#" else "." for ch in row) for row in rows]
    objects: list[tuple[Footprint, tuple[float, float]]] = [
        (Box(1.0, 1.0), (float(c), -float(r))) for r, row in enumerate(rows)
        for c, ch in enumerate(row) if ch == "x"]
    tiles, space = _space(walls, objects, clearance=1e-4)
    cells = sorted((float(c), -float(r)) for r, row in enumerate(rows)
                   for c, ch in enumerate(row) if ch == ".")
    assume(cells)
    p, q = cells[a % len(cells)], cells[b % len(cells)]
    old, new = tiles.distance(p, q), space.distance(p, q)
    assert math.isfinite(old) == math.isfinite(new)
    if math.isfinite(old):
        assert new == pytest.approx(old, abs=0.01)
        assert new == pytest.approx(space.distance(q, p))


def test_a_hall_of_many_objects_searches_only_near_the_task(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Past EXACT_CORNERS * VERTICES_PER_CORNER vertices (here cut to 100, the hall has 144)
    the search keeps to those within the ellipse of a bound round the task's ends: the same
    length as the search over all of them for tasks whose ellipse holds few; one across the
    hall, whose ellipse holds nearly all, gets the tile estimate."""
    lattice: list[tuple[Footprint, tuple[float, float]]] = [
        (Box(0.5, 0.5), (float(c), -float(r))) for c in range(2, 14, 2) for r in range(2, 8, 2)]
    rows = ["#" * 16] + ["#" + "." * 14 + "#"] * 8 + ["#" * 16]
    monkeypatch.setattr(efficiency, "EXACT_CORNERS", 50)
    tiles, hall = _space(rows, lattice)
    assert len(hall.vertices) > efficiency.EXACT_CORNERS * efficiency.VERTICES_PER_CORNER
    near = [((3.0, -3.0), (7.0, -5.4)), ((8.0, -1.0), (12.0, -3.0))]
    across = ((1.0, -1.0), (13.0, -7.0))
    bounded = [hall.distance(p, q) for p, q in near]
    assert hall.distance(*across) == pytest.approx(tiles.distance(*across))
    monkeypatch.setattr(efficiency, "EXACT_CORNERS", 100_000)
    exact = [hall.distance(p, q) for p, q in near]
    assert bounded == pytest.approx(exact)
    assert all(math.dist(p, q) < d for (p, q), d in zip(near, exact, strict=True))
    assert math.dist(*across) < hall.distance(*across) < tiles.distance(*across)


def _corridor_run(detour: bool, slower: float = 1.0) -> tuple[StreamHeader, list[Sample]]:
    """A 1 m corridor with a 0.2 m pillar in a tile's centre, a loop of corridors below it
    (ROOM_LOOP), and a run from one end of the top corridor to the other: past the pillar
    (6.0 m), or round the loop (10 m) as a navigator that thinks the pillar closes the
    corridor would drive), ``slower`` times slower than the allowed 0.26 m/s."""
    rows = ["#########",
            "#.......#",
            "#.#####.#",
            "#.......#",
            "#########"]
    placed = [(ObservedObject(f"w{r}_{c}", "wall", "wall", Tile(), 1.0), (float(c), -float(r)))
              for r, row in enumerate(rows) for c, ch in enumerate(row) if ch == "#"]
    placed.append((ObservedObject("pillar", "static", "pillar", Cylinder(0.1), 1.0), (4.0, -1.0)))
    floors = tuple((f"f{r}_{c}", float(c), -float(r)) for r, row in enumerate(rows)
                   for c, ch in enumerate(row) if ch != "#")
    goal = GoalFacts("g0", 7.0, -1.0, None, 0.25, 0.26, 200.0)
    facts = MissionFacts((goal,), 1, 300.0, 0.26, 1.82, None)
    header = StreamHeader(SCHEMA_VERSION, "synthetic", "synthetic", 0, 10.0, ROBOT,
                          tuple(o for o, _ in placed), 1.0, floors, mission_facts=facts)
    corners = [(1.0, -1.0), (1.0, -3.0), (7.0, -3.0), (7.0, -1.0)] if detour else \
        [(1.0, -1.0), (3.5, -1.0), (4.0, -1.3), (4.5, -1.0), (7.0, -1.0)]
    route: list[tuple[float, float]] = []
    for (x0, y0), (x1, y1) in zip(corners, corners[1:], strict=False):
        steps = max(1, round(math.dist((x0, y0), (x1, y1)) * slower / 0.026))
        route += [(x0 + (x1 - x0) * k / steps, y0 + (y1 - y0) * k / steps) for k in range(steps)]
    route.append(corners[-1])
    route += [corners[-1]] * 2
    poses = np.array([(x, y, 0.0) for _, (x, y) in placed])
    n = len(route)
    events = {0: (MissionEvent("begin", 0.0), MissionEvent("task_start", 0.0, "g0", 0)),
              n - 2: (MissionEvent("task_success", (n - 2) / 10.0, "g0", 0),),
              n - 1: (MissionEvent("end", (n - 1) / 10.0),)}
    samples = [Sample(i, i / 10.0, (x, y, 0.0), (0.0, 0.0, 0.0), poses, np.zeros_like(poses),
                      RobotBelief((x, y, 0.0), (0.0, 0.0), 3.5, None, NavState.ACTIVE, None),
                      events.get(i, ())) for i, (x, y) in enumerate(route)]
    return header, samples


@pytest.mark.parametrize(("detour", "tiles_only", "status"), [
    (True, False, "fail"), (True, True, "pass"), (False, False, "pass"), (False, True, "pass")])
def test_a_detour_fails_efficient_path_against_the_real_free_space(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, detour: bool, tiles_only: bool,
        status: str) -> None:
    """Issue 25: the detour round the loop is 10 m against 6 m past the pillar. Judged
    against the robot's real free space (``RuntimeModel.FOOTPRINT_PATHS``) it fails
    EFFICIENT_PATH (1.66 > 1.5); against the tile estimate, which closes the pillar's tile,
    the same run passes (1.2: round the loop is the shortest path there); the run past the
    pillar passes either way."""
    monkeypatch.setattr(RuntimeModel, "FOOTPRINT_PATHS", not tiles_only)
    header, samples = _corridor_run(detour)
    _, result = monitor(header, samples, tmp_path / "a")
    verdicts = {v.requirement: v.status for v in result.verdicts}
    assert verdicts["MISSION_GOALS_REACHED"] == "pass"
    assert verdicts["EFFICIENT_PATH"] == status
    _, again = monitor(header, samples, tmp_path / "b")  # the same stream, the same bytes
    assert (tmp_path / "a" / "events.csv").read_bytes() == \
        (tmp_path / "b" / "events.csv").read_bytes()
    assert again.measurements["efficiency"] == result.measurements["efficiency"]
    figures = result.measurements["efficiency"][0]
    assert figures["shortest"] == pytest.approx(8.16 if tiles_only else 6.0, abs=0.1)
    if not detour:  # the tile estimate reads the drive past the pillar far below 1
        assert (figures["path_ratio"] < 0.8) if tiles_only else \
            (1.0 < figures["path_ratio"] < 1.05)


@pytest.mark.parametrize(("ratio", "status"), [(2.4, "pass"), (3.3, "fail")])
def test_time_to_goal_fails_a_navigator_three_times_slower_than_the_allowed_speed(
        tmp_path: Path, ratio: float, status: str) -> None:
    """max_time_ratio 3.0 (issue 25 follow-up): the reference's worst time ratio is 2.38 over
    1,000 medium runs; a crawler ~2.8 times slower than it passed the old 4.0. The drive past
    the pillar (6.05 m; the tile estimate judged with reads 8.16 m) slowed to take 2.4 times
    that estimate at the allowed speed passes, 3.3 times fails."""
    header, samples = _corridor_run(False, ratio * 8.16 / 6.05)
    _, result = monitor(header, samples, tmp_path)
    verdicts = {v.requirement: v.status for v in result.verdicts}
    assert verdicts["MISSION_GOALS_REACHED"] == "pass"
    assert verdicts["EFFICIENT_PATH"] == "pass"
    assert verdicts["TIME_TO_GOAL"] == status
    assert result.measurements["efficiency"][0]["time_ratio"] == pytest.approx(ratio, rel=0.03)


def test_a_header_without_walls_or_static_objects_falls_back_to_the_tiles() -> None:
    """A trace whose header lists no wall or static object (nothing to inflate): the
    tile estimate over its floors."""
    floors = tuple((f"f{c}", float(c), 0.0) for c in range(4))
    header = StreamHeader(SCHEMA_VERSION, "synthetic", "synthetic", 0, 10.0, ROBOT, (), 1.0,
                          floors)
    model = RuntimeModel(header)
    s = Sample(0, 0.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), np.zeros((0, 3)), np.zeros((0, 3)),
               RobotBelief((0.0, 0.0, 0.0), (0.0, 0.0), 3.5, None, NavState.ACTIVE, None))
    tiles = model.tile_space(s)
    assert tiles is not None
    space = model.free_space(s, tiles)
    assert space is tiles
    assert space.distance((0.0, 0.0), (3.0, 0.0)) == pytest.approx(3.0)


def test_a_task_is_judged_against_the_shortest_path_to_its_goal() -> None:
    goal = GoalFacts("g", 4.0, 0.0, None, 0.25, 0.26, 60.0)
    task = TaskProgress((0.0, 0.0), 10.0, goal, travelled=8.0)
    judged = judge_task(task, 10.0 + 32.0, 4.0, 0.25)
    assert judged.shortest == pytest.approx(4.0)
    assert judged.path_ratio == pytest.approx(2.0)
    assert judged.time_ratio == pytest.approx(2.0)  # 32 s against 4 m at 0.25 m/s
    # a straight drive onto a goal 1 m away reads 0.9, not 0.9 / (1 - 0.25) = 1.2
    short = judge_task(TaskProgress((0.0, 0.0), 0.0, goal, travelled=0.9), 5.0, 1.0, 0.25)
    assert short.path_ratio == pytest.approx(0.9)
    near = judge_task(TaskProgress((0.0, 0.0), 0.0, goal), 5.0, 0.7, 0.25)
    assert near.path_ratio == near.time_ratio == 0.0  # less its tolerance too near to judge


def test_turning_in_place_counts_only_near_the_goal() -> None:
    goal = GoalFacts("g", 4.0, 0.0, None, 0.25, 0.26, 60.0)
    task = TaskProgress((0.0, 0.0), 0.0, goal)
    task.observe((0.0, 0.0), 0.0, 0.0, 1.0, 1.0)  # far from the goal: the start's turn
    task.observe((3.9, 0.0), 0.0, 0.0, -1.0, 1.0)  # in place near the goal
    task.observe((3.9, 0.0), 0.0, 0.2, 1.0, 1.0)  # driving: no turn in place
    assert task.spin == pytest.approx(1.0)


ROOM = """room hall {
    grid g {
        legend {
            "S" = floor start
            "G" = floor goal
            "W" = floor start_w
        }
        "##########"
        "#........#"
        "#WS.....G#"
        "#........#"
        "##########"
    }
    robot r : turtlebot3_waffle on start heading 0
}
"""
MISSION = """mission across in "hall.room" {
    goal here at start tolerance 0.25 timeout 10
    goal there at goal tolerance 0.25 timeout 120
}
"""
NAVIGATORS = """
import math

from rei.runtime.messages import NavState
from rei.runtime.robot.contract import GoalFeedback, NavGoal, VelocityCommand
from rei.runtime.robot.navigator.reference import ReferenceNavigator


class Detour(ReferenceNavigator):
    \"\"\"For goals more than 1 m away: drives two thirds of the way, back to where it got the
    goal, then to the goal (a behaviour tree that restarts its navigation subtree once).\"\"\"

    def send_goal(self, goal):
        self._real, self._legs = goal, None
        super().send_goal(goal)

    def feedback(self):
        if getattr(self, "_legs", None):
            return GoalFeedback(NavState.ACTIVE, self._real.name, None, "detour")
        return super().feedback()

    def step(self, observation):
        x, y, _ = observation.odom_pose
        goal = getattr(self, "_real", None)
        if goal is not None and self._legs is None:
            self._legs = []
            if math.hypot(goal.x - x, goal.y - y) > 1.0:
                self._legs = [NavGoal("detour", x + 2 * (goal.x - x) / 3,
                                      y + 2 * (goal.y - y) / 3, None, 0.3, goal.timeout),
                              NavGoal("back", x, y, None, 0.3, goal.timeout)]
                super().send_goal(self._legs[0])
        elif self._legs and super().feedback().state == NavState.SUCCEEDED:
            self._legs.pop(0)
            super().send_goal(self._legs[0] if self._legs else goal)
        return super().step(observation)


class Crawls(ReferenceNavigator):
    \"\"\"The reference at a fifth of its speed (a velocity smoother's limit set 5x too low).\"\"\"

    def step(self, observation):
        cmd = super().step(observation)
        return VelocityCommand(cmd.linear / 5, cmd.angular)


class OscillatesAtGoal(ReferenceNavigator):
    \"\"\"Turns back and forth in place for 10 s near each goal more than 1 m from where it
    got it, before it goes on and reports success.\"\"\"

    def send_goal(self, goal):
        self._from, self._since = None, None
        super().send_goal(goal)

    def step(self, observation):
        x, y, _ = observation.odom_pose
        goal = self._tracker.goal
        if goal is not None and self._tracker.running:
            if self._from is None:
                self._from = (x, y)
            far = math.hypot(goal.x - self._from[0], goal.y - self._from[1]) > 1.0
            if far and math.hypot(goal.x - x, goal.y - y) <= 0.3:
                self._since = self._since if self._since is not None else observation.time
                if observation.time - self._since < 10.0:
                    super().step(observation)  # keeps its goal state; the command is replaced
                    phase = int(observation.time - self._since) % 2
                    return VelocityCommand(0.0, 0.8 if phase else -0.8)
        return super().step(observation)
"""


def _summary(tmp: Path, controller: str, mission: str = MISSION,
             *extra: str) -> dict[str, Any]:
    tmp.mkdir(parents=True)
    (tmp / "hall.room").write_text(ROOM)
    (tmp / "across.mission").write_text(mission)
    (tmp / "navs.py").write_text(NAVIGATORS)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp), str(REPO)])}
    done = subprocess.run([sys.executable, "-m", "rei.runtime.commands", "run",
                           str(tmp / "across.mission"), "-o", str(tmp / "out"), "--controller",
                           controller, "--no-variation", "-q", *extra],
                          capture_output=True, text=True, env=env, timeout=600, check=False)
    summary: dict[str, Any] = json.loads((tmp / "out" / "summary.json").read_text())
    assert summary["outcome"] == "completed", done.stderr
    return summary


def _run(tmp: Path, controller: str) -> dict[str, str]:
    return {v["requirement"]: v["status"] for v in _summary(tmp, controller)["verdicts"]}


EFFICIENCY = ("EFFICIENT_PATH", "TIME_TO_GOAL", "NO_SPIN_AT_GOAL")


@pytest.mark.slow
@pytest.mark.parametrize(("controller", "fails"), [
    ("reference", None),
    ("navs:Detour", "EFFICIENT_PATH"),
    ("navs:Crawls", "TIME_TO_GOAL"),
    ("navs:OscillatesAtGoal", "NO_SPIN_AT_GOAL"),
])
def test_each_efficiency_requirement_fails_its_navigator_and_the_reference_passes(
        tmp_path: Path, controller: str, fails: str | None) -> None:
    status = _run(tmp_path / "run", controller)
    assert status["MISSION_GOALS_REACHED"] == "pass"  # every one reaches its goals
    assert {r: status[r] for r in EFFICIENCY} == {
        r: ("fail" if r == fails else "pass") for r in EFFICIENCY}


BEHIND = """mission behind in "hall.room" {
    goal here at start tolerance 0.3 timeout 10
    goal back at start_w tolerance 0.3 timeout 60
}
"""


@pytest.mark.slow
@pytest.mark.parametrize(("controller", "worst", "verdict"), [
    ("reference", (0.8, 1.1), "pass"),
    ("tests.robot.arcs_around:ArcsAround", (1.3, 2.0), "fail"),
])
def test_the_reference_turns_on_the_spot_to_a_goal_behind_it(
        tmp_path: Path, controller: str, worst: tuple[float, float], verdict: str) -> None:
    """Issue 22: a short task whose goal lies behind the robot. The reference turns on the
    spot and drives straight (about the shortest path less its 0.1 m stop short of the goal);
    looping round on the local planner's tightest forward arc drives ~0.4 m more on 1 m, the
    cause of 18 of 1,000 medium runs failing EFFICIENT_PATH. At a bound of 1.25 the loop
    fails and the reference passes."""
    summary = _summary(tmp_path / "run", controller, BEHIND, "--param", "max_path_ratio=1.25")
    back = [e for e in summary["measurements"]["efficiency"] if e["task"] == "back"]
    assert back[0]["shortest"] == pytest.approx(1.0, abs=0.05)
    assert worst[0] <= back[0]["path_ratio"] <= worst[1]
    status = {v["requirement"]: v["status"] for v in summary["verdicts"]}
    assert status["MISSION_GOALS_REACHED"] == "pass"
    assert status["EFFICIENT_PATH"] == verdict
