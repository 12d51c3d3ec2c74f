"""Building one room and its mission from one row of parameters, valid by construction.

The order of the steps is what makes the result valid without search:

1. the floor plan (rectangle, L, or two rooms joined by a doorway), walls around it;
2. the robot's floor and the goals, each at least ``spacing`` metres from the previous;
3. the humans' trajectories, whose spline and control polygon keep a clearance from every
   wall; the tiles they sweep are reserved;
4. the objects, on tiles not reserved, each accepted only if the free floor stays one
   connected piece — so every goal and every trajectory vertex stays reachable;
5. the robot's route through the goals on the inflated floor graph, the descriptors, and
   (for ``crossing=cross``) a check that some human crosses that route.

A step that cannot be done (no floor far enough, no clear trajectory, no tile left for an
object) fails the *attempt* with a reason; the caller retries with a new random stream a
bounded number of times. All randomness comes from the ``random.Random`` passed in.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass, replace

import numpy as np

from rei.catalogue import Catalogue, Cylinder, ObjectType
from rei.generators.rooms.descriptors import (
    Descriptors,
    Obstacle,
    Scene,
    UnreachableGoals,
    describe,
    robot_route,
)
from rei.generators.rooms.geometry import (
    Cell,
    CellMask,
    bfs_route,
    catmull_rom,
    disc_touches,
    entries,
    polyline,
    stays_connected,
    swept_cells,
)
from rei.generators.rooms.space import MIX_BEHAVIOURS, NO_STRESSOR, RoomParameters, door_width
from rei.generators.rooms.stressors import (
    ROW_TYPE,
    Bodies,
    StressorFailed,
    StressorLayout,
    StressorPlan,
    plan_layout,
    time_layout,
)
from rei.lang.room.checks import rotated_half_extents

GRID = "area"
ROBOT_TYPE = "turtlebot3_waffle"
ROW_PREFIX = "row_"
"""The names of a stressor's row objects begin so (the row's gap is the stressor: a search's
placement shift leaves them be, rei.generators.rooms.scenario)."""
HEADINGS = (0.0, 90.0, 180.0, 270.0, 45.0, 135.0, 30.0, 60.0, 120.0, 150.0)
HUMAN_MIN_STEP = 2.0
"""Tiles between consecutive control vertices of a human's trajectory."""
HUMAN_TRIES = 30
CHECK_STEP = 0.2
"""Metres between the points where a trajectory's clearance is checked: a disc of 0.35 m
moving 0.2 m between checks can dip at most 1.5 cm deeper than checked, inside the 0.1 m
margin over the human's 0.25 m radius."""


class AttemptFailed(Exception):
    """This attempt could not finish; ``reason`` says which step and why."""

    def __init__(self, option: str, reason: str) -> None:
        super().__init__(reason)
        self.option = option
        """The command-line option whose level made this step fail."""
        self.reason = reason


@dataclass(frozen=True)
class PlacedObjectPlan:
    name: str
    type: str
    cell: Cell
    heading: float
    offset: tuple[float, float] = (0.0, 0.0)
    """m from the tile's centre (a search's object shift, generators/rooms/scenario.py)."""


@dataclass(frozen=True)
class HumanPlan:
    name: str
    vertices: tuple[Cell, ...]
    loop: bool
    total_time: float
    behaviour: str = "scripted"
    start_s: float = 0.0
    """When the human passes its first vertex (a search's start phase,
    generators/rooms/scenario.py); 0 keeps the ``total`` form the generator writes."""
    offsets: tuple[tuple[float, float], ...] = ()
    """m from each vertex's tile centre (a search's path shift); () for none."""


@dataclass(frozen=True)
class RoomPlan:
    params: RoomParameters
    rows: tuple[str, ...]
    """The grid block's rows: '#' wall, '.' floor, ' ' outside."""
    floors: frozenset[Cell]
    robot: Cell
    robot_heading: float
    objects: tuple[PlacedObjectPlan, ...]
    humans: tuple[HumanPlan, ...]
    goals: tuple[Cell, ...]
    route: tuple[Cell, ...]
    descriptors: Descriptors
    stressor: StressorPlan | None = None
    goal_offsets: tuple[tuple[float, float], ...] = ()
    """m from each goal's tile centre (a search's goal shift); () for none."""


@dataclass(frozen=True)
class CatalogueFacts:
    """What construction needs from the catalogue, computed once per suite."""

    types: dict[str, ObjectType]
    headings: dict[str, tuple[float, ...]]
    """Headings at which each static type fits its tile."""
    bodies: Bodies
    """The robot's and the cart's sizes and the robot's top speed, for stressor timing."""

    @staticmethod
    def of(catalogue: Catalogue, tile: float = 1.0) -> CatalogueFacts:
        types = {n: catalogue.types[n] for n in catalogue.names("static")}
        headings: dict[str, tuple[float, ...]] = {}
        for name, otype in types.items():
            if isinstance(otype.footprint, Cylinder):  # turning a round thing changes nothing
                headings[name] = (0.0,) if otype.footprint.radius <= tile / 2 else ()
                continue
            fits = tuple(h for h in HEADINGS
                         if max(rotated_half_extents(otype, h)) <= tile / 2 - 1e-6)
            headings[name] = fits
        return CatalogueFacts(types, headings, Bodies.of(catalogue, ROBOT_TYPE))


def cell_name(cell: Cell) -> str:
    """The grid's name of a cell: row from the top (j = -row), column = i."""
    return f"{GRID}_{-cell[1]}_{cell[0]}"


def floor_plan(params: RoomParameters, rng: random.Random) -> set[Cell]:
    """Floor cells in the layout frame; rows 1..H from the top are j = -1..-H, cols i = 1..W."""
    w, h = params.width, params.height
    cells = {(c, -r) for r in range(1, h + 1) for c in range(1, w + 1)}
    if params.shape == "L":
        cw, ch = w // 2, h // 2
        right, top = rng.random() < 0.5, rng.random() < 0.5
        cols = range(w - cw + 1, w + 1) if right else range(1, cw + 1)
        rows = range(1, ch + 1) if top else range(h - ch + 1, h + 1)
        cells -= {(c, -r) for r in rows for c in cols}
    elif params.shape == "joined":
        if w >= h:  # a wall column across the height, with a doorway
            across, at = h, _split(w, rng)
            door = rng.randrange(1, across - door_width(across) + 2)
            wall = {(at, -r) for r in range(1, h + 1)
                    if not door <= r < door + door_width(across)}
        else:
            across, at = w, _split(h, rng)
            door = rng.randrange(1, across - door_width(across) + 2)
            wall = {(c, -at) for c in range(1, w + 1)
                    if not door <= c < door + door_width(across)}
        cells -= wall
    return cells


def _split(length: int, rng: random.Random) -> int:
    """Where the dividing wall goes: in the middle third, so neither room is a sliver."""
    low, high = max(2, length // 3 + 1), max(2, length - length // 3)
    return low + rng.randrange(high - low + 1)


def grid_rows(params: RoomParameters, floors: set[Cell],
              inner_walls: frozenset[Cell] = frozenset()) -> tuple[str, ...]:
    """The grid block: floors, and walls around the floor plan as it was before
    ``inner_walls`` (floors a stressor turned into walls) were taken out of it, so the outer
    wall stays closed behind them."""
    plan = floors | inner_walls
    walls = {(i + di, j + dj) for i, j in plan for di in (-1, 0, 1) for dj in (-1, 0, 1)}
    rows = []
    for r in range(0, params.height + 2):
        rows.append("".join("." if (c, -r) in floors else "#" if (c, -r) in walls else " "
                            for c in range(0, params.width + 2)))
    return tuple(rows)


def _choose_goals(params: RoomParameters, floors: set[Cell], rng: random.Random) -> list[Cell]:
    ordered = sorted(floors)
    reach = params.spacing - 1e-9
    # Only floors with some floor far enough away can lead on to a next goal.
    coords = np.asarray(ordered, dtype=float)
    # The farthest floor from any point is a vertex of the floors' convex hull, and a hull
    # vertex lacks a floor neighbour on a horizontal and on a vertical side.
    corners = np.asarray([c for c in ordered
                          if ((c[0] - 1, c[1]) not in floors or (c[0] + 1, c[1]) not in floors)
                          and ((c[0], c[1] - 1) not in floors or (c[0], c[1] + 1) not in floors)],
                         dtype=float)
    gaps = coords[:, None, :] - corners[None, :, :]
    can_go_on = np.sqrt((gaps ** 2).sum(axis=2).max(axis=1)) >= reach
    onward_idx = np.flatnonzero(can_go_on).tolist()
    if not onward_idx:
        raise AttemptFailed("spacing", f"no two floors {params.spacing:g} m apart")
    chosen = [onward_idx[rng.randrange(len(onward_idx))]]
    for k in range(params.goals - 1):
        prev = coords[chosen[-1]]
        ok = np.hypot(coords[:, 0] - prev[0], coords[:, 1] - prev[1]) >= reach
        if k < params.goals - 2:
            ok &= can_go_on
        ok[chosen] = False
        far = np.flatnonzero(ok).tolist()
        if not far:
            raise AttemptFailed("spacing",
                                f"no floor {params.spacing:g} m from goal {len(chosen)}")
        chosen.append(far[rng.randrange(len(far))])
    return [ordered[i] for i in chosen]


def _human(params: RoomParameters, index: int, floors: set[Cell], outside: CellMask,
           taken: set[Cell], robot: Cell, base_route: list[Cell], rng: random.Random,
           goals: frozenset[Cell] = frozenset()) -> tuple[HumanPlan, set[Cell]]:
    ordered = sorted(floors)
    convex = params.shape == "rect"
    for _ in range(HUMAN_TRIES):
        vertices: list[Cell] = []
        if params.crossing == "cross" and len(base_route) > 2:
            # Two vertices on either side of a cell of the robot's route: the human walks
            # across it.
            k = rng.randrange(1, len(base_route) - 1)
            p, prev, nxt = base_route[k], base_route[k - 1], base_route[k + 1]
            d = (nxt[0] - prev[0], nxt[1] - prev[1])
            n = (-d[1], d[0]) if d != (0, 0) else (1, 0)
            n = (int(math.copysign(1, n[0])) if n[0] else 0,
                 int(math.copysign(1, n[1])) if n[1] else 0)
            span = rng.randrange(1, 4)
            a = (p[0] + span * n[0], p[1] + span * n[1])
            b = (p[0] - span * n[0], p[1] - span * n[1])
            if a not in floors or b not in floors:
                continue
            vertices = [a, b] if rng.random() < 0.5 else [b, a]
        else:
            vertices = [ordered[rng.randrange(len(ordered))]]
        start = vertices[0]
        if start in taken or math.dist(start, robot) < 2.0:
            continue
        while len(vertices) < params.vertices:
            prev = vertices[-1]
            for _try in range(12):
                cand = ordered[rng.randrange(len(ordered))]
                if math.dist(cand, prev) < HUMAN_MIN_STEP:
                    continue
                # In a rectangle every chord between floor centres keeps 0.5 m from the
                # walls; other shapes need the check.
                if convex or not disc_touches(polyline([prev, cand], False, CHECK_STEP),
                                              outside):
                    vertices.append(cand)
                    break
            else:
                break
        if len(vertices) < params.vertices:
            continue
        if params.loop and math.dist(vertices[-1], vertices[0]) < 1.0:
            continue
        # An open path's last vertex is where the human stands for the rest of the run: on a
        # goal's tile it stands on the robot's goal for ever, and where that tile is a
        # corner no reactive human can leave it with the robot waiting (issue 22: medium
        # room 394's walker stood on goal_4 until the reference aborted, in both repeats).
        if not params.loop and vertices[-1] in goals:
            continue
        points = [(float(i), float(j)) for i, j in vertices]
        spline = catmull_rom(points, params.loop, CHECK_STEP)
        straight = polyline(points, params.loop, CHECK_STEP)
        if disc_touches(spline, outside) or disc_touches(straight, outside):
            continue
        steps = spline[1:] - spline[:-1]
        length = float(np.hypot(steps[:, 0], steps[:, 1]).sum())
        total = max(1.0, round(length / params.speed, 1))  # tiles are 1 m
        swept = swept_cells(spline) | swept_cells(straight)
        return HumanPlan(f"walker_{index + 1}", tuple(vertices), params.loop, total,
                         behaviour_of(params, index)), swept
    raise AttemptFailed("vertices", f"no clear trajectory for human {index + 1} after "
                                    f"{HUMAN_TRIES} tries")


def behaviour_of(params: RoomParameters, index: int) -> str:
    """Human ``index``'s behaviour: the level, or for ``mix`` yielding and social in turn
    (by index, not drawn, so the mix never changes the room's random stream)."""
    if params.behaviour == "mix":
        return MIX_BEHAVIOURS[index % len(MIX_BEHAVIOURS)]
    return params.behaviour


def construct(params: RoomParameters, facts: CatalogueFacts, rng: random.Random,
              side: str | None = None) -> RoomPlan:
    """One attempt; AttemptFailed when a step cannot be done with this random stream.
    ``side``: the side of the route a stressor's mover ends up beside (None: either)."""
    floors = floor_plan(params, rng)
    w, h = params.width, params.height
    box = {(c, -r) for r in range(-1, h + 3) for c in range(-1, w + 3)}
    outside = CellMask(box - floors)
    goals = _choose_goals(params, floors, rng)
    robot = goals[0]
    layout: StressorLayout | None = None
    row_cells: set[Cell] = set()
    if params.stressor != NO_STRESSOR:
        try:
            layout = plan_layout(params, floors, goals,
                                 max(facts.types[ROW_TYPE].footprint.half_extents()), rng,
                                 side)
        except StressorFailed as exc:
            raise AttemptFailed("stressor", str(exc)) from None
        floors -= layout.walls
        row_cells = {o.cell for o in layout.row}
        outside = CellMask((box - floors) | row_cells)

    stops = goals + ([goals[0]] if params.cycles > 1 else [])
    crossing_wanted = params.crossing == "cross" and params.humans > 0
    base = (bfs_route(floors, stops) if crossing_wanted else None) or [robot]
    reserved: set[Cell] = set(goals)
    humans: list[HumanPlan] = []
    taken = {robot}
    if layout is not None:
        reserved |= layout.keep_free | row_cells
        if layout.mover is not None:
            taken |= set(layout.mover.vertices)
    for k in range(params.humans):
        human, swept = _human(params, k, floors, outside, taken, robot, base, rng, frozenset(goals))
        humans.append(human)
        taken.add(human.vertices[0])
        reserved |= swept | set(human.vertices)

    free = set(floors) - row_cells
    wanted = params.object_count(len(floors))
    candidates = sorted(floors - reserved)
    rng.shuffle(candidates)
    objects: list[PlacedObjectPlan] = []
    counts: dict[str, int] = {}
    if layout is not None:
        objects += [PlacedObjectPlan(f"{ROW_PREFIX}{o.type}_{k + 1}", o.type, o.cell, o.heading)
                    for k, o in enumerate(layout.row)]
        wanted += len(layout.row)
    for cell in candidates:
        if len(objects) == wanted:
            break
        if not stays_connected(free, cell):
            continue
        free.discard(cell)
        type_name = params.mix[rng.randrange(len(params.mix))]
        fits = facts.headings[type_name]
        if not fits:
            raise AttemptFailed("mix", f"type '{type_name}' fits its tile at no heading")
        counts[type_name] = counts.get(type_name, 0) + 1
        objects.append(PlacedObjectPlan(f"{type_name}_{counts[type_name]}", type_name, cell,
                                        fits[rng.randrange(len(fits))]))
    if len(objects) < wanted:
        raise AttemptFailed("objects", f"room for only {len(objects)} of {wanted} objects with "
                                       f"the goals and trajectories kept reachable")

    scene = Scene(
        tile=1.0, floors=frozenset(floors),
        obstacles=tuple(Obstacle(o.cell, facts.types[o.type].footprint, o.heading)
                        for o in objects),
        goals=tuple(goals), cycles=params.cycles,
        trajectories=tuple((hp.vertices, hp.loop) for hp in humans), humans=len(humans))
    try:
        route = robot_route(scene)
    except UnreachableGoals:  # cannot happen while the free floor stays connected
        raise AttemptFailed("objects", "goals not reachable in order") from None
    stressor: StressorPlan | None = None
    if layout is not None:
        try:
            stressor = time_layout(layout, route, params, facts.bodies)
        except StressorFailed as exc:
            raise AttemptFailed("stressor", str(exc)) from None
        if stressor.mover is not None:
            scene = replace(scene, trajectories=(
                *scene.trajectories, (tuple(c for c, _ in stressor.mover.vertices), False)),
                humans=scene.humans + (stressor.mover.role == "human"))
    descriptors = describe(scene, route)
    if params.crossing == "cross" and humans:
        corridor = set(route)
        for hp in humans:
            pts = [(float(i), float(j)) for i, j in hp.vertices]
            if entries(catmull_rom(pts, hp.loop), corridor, hp.loop) == 0:
                raise AttemptFailed("crossing", f"{hp.name} does not cross the robot's route")
    first_step = next((c for c in route if c != robot), None)
    heading = 0.0
    if first_step is not None:
        heading = math.degrees(math.atan2(first_step[1] - robot[1], first_step[0] - robot[0]))
        heading = float(round(heading) % 360)
    inner = layout.walls if layout is not None else frozenset()
    return RoomPlan(params, grid_rows(params, floors, inner), frozenset(floors), robot, heading,
                    tuple(objects), tuple(humans), tuple(goals), tuple(route), descriptors,
                    stressor)

