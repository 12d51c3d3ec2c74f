"""Stressor scenarios on a generated room's first leg: what a navigator acting on late
perception, or planning without its footprint, runs into — and a careful one passes.

* ``emerge``: a wall stub beside the route hides a person standing right behind it; the
  person steps into the route and walks a tile towards the robot, then off the route.
* ``oncoming``: the route runs through a one-tile corridor (walls turned out of floors on
  both sides for ``CORRIDOR_LENGTH`` tiles); a person walks it towards the robot and steps
  aside past its near end.
* ``standing``: the same one-tile corridor, with a person standing in its middle tile, looking
  at a phone: a scripted person, who does not give way. It stands there until ``STAND_FOR``
  seconds after the robot's planned arrival at the corridor, then walks on out of the far end
  and steps aside. A navigator must wait for it, recover (back up, turn, re-plan) or go round
  the corridor, and must neither drive into it nor give up the goal while it stands there.
* ``crossing``: a cart (a scripted dynamic object) crosses the route at a right angle from
  two tiles off it and is parked on the tile beside the route on the other side, where the
  robot passes it.
* ``doorway``: a doorway beside a straight stretch of the route (wall stubs either side of
  the tile beside it, and of the tile behind that), a person standing in it one tile back; the
  person steps into the doorway, towards the route, when the robot comes within a
  distance of the route tile level with it (a start trigger, ``when robot within D of
  FLOOR``): the robot's laser first shows the person through the opening 60-120 degrees off
  its heading, within a metre of its footprint. It is the one stressor timed by where the
  robot really is, so it tests a navigator blind on that side, or late, at every pace.
* ``gap``: a row of tables across the first leg, turned so two neighbours leave a slot
  narrower than the robot where the straight line between the goals crosses the row, and one
  open tile at least two tiles from the slot: the shortest way for a point goes through the
  slot, the robot's goes round through the opening.

Sides (all but the gap): each mover ends up standing on a tile beside the robot's route —
the emerging person where it stepped aside, the parked cart, the oncoming person past the
corridor's near end, the doorway's person in its doorway — so the robot passes it within a
metre, on its left or on its right. The caller says which (``side``, ``SIDES``): ``side_of``
alternates it over a suite's mover rooms, so a suite with two of them has an encounter on
each side of the route; the first three movers come from the other side, so they cross in
front of the robot either way (the doorway's person comes from and stays on its side). None
leaves the side to the random stream.

Timing (emerge, oncoming, crossing): the encounter is timed from the robot's *planned*
arrival — its route on the static map (the inflated floor graph, as the descriptors walk
it) driven at ``NOMINAL_SPEED`` after ``START_DELAY`` — so the mover reaches the meeting
point when the planned robot is ``lead`` metres before it. The mover waits on its first
tile until then: the room file lists the wait as vertices ``HOLD_STEP`` seconds apart (so
the per-run start delay, at most one vertex interval, stays short) and ends it with two
vertices ``SETTLE`` seconds apart (so the spline stands still while waiting, instead of
swinging back and forth). The cart is scripted, so it is also timed to have cleared the
robot's lane before the robot could get there at its top speed: a careful robot is never
hit, it only has to wait. People added here are ``yielding`` humans (they stop for the
robot and step aside), the fairness every generated human has.

Timing (doorway): by the robot's real position. The person's trajectory starts when the
robot's centre comes within a distance D of the route tile level with the doorway — D
chosen so that a robot at its top speed is ``DOORWAY_AHEAD`` before level when the person,
``DOORWAY_SEEN`` into its step, comes within REACTION_TIME's 1.05 m of the footprint; a
slower robot is farther back then (the person is seen still more ahead). Nothing waits on
a planned arrival, so the encounter is the same whatever pace or path the navigator takes.

All randomness comes from the ``random.Random`` passed in; this module never touches files,
never imports the runtime, and never changes a room without keeping its floor connected.
"""

from __future__ import annotations

import math
import random
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, replace

from rei.catalogue import Catalogue
from rei.generators.rooms.geometry import Cell, fast_route, is_connected
from rei.generators.rooms.space import RoomParameters

NOMINAL_SPEED = 0.25
"""m/s the robot is planned to drive at: the reference navigator's pace on a free straight
(about 2.5 m in the first 10 s, bench/RESULTS.md), just below the Waffle's top speed."""
START_DELAY = 1.0
"""s the robot is planned to need before it moves (first command, acceleration)."""
HOLD_STEP = 2.0
"""s between the vertices that make a mover wait on its first tile."""
SETTLE = 0.5
"""s between the last two waiting vertices (a spline leaves a vertex at the mean of its two
chord velocities; with the same tile on both sides of the wait, it stands still there)."""
MIN_WAIT = 1.0
"""s a mover waits at least: a shorter wait means the meeting point is too near the start."""
PERSON_LEAD = 1.5
"""m before the meeting point the planned robot is when a person reaches it."""
ONCOMING_LEAD = 2.5
"""m before the corridor the planned robot is when the oncoming person reaches its near end."""
ONCOMING_CLEAR = 0.0
"""m before the tile in front of the corridor the robot, at its top speed, may be at the
latest when the oncoming person, at its slowest and latest, has stepped aside beside that
tile: a person and a robot face to face inside a one-tile corridor would wait for each other
for good (outside it the person has room to give way)."""
HUMAN_SLOWEST = 0.85
"""The slowest per-run speed scale of a human (runtime/simulation/animator/variation.py,
1 - 0.15)."""
CART_LEAD = 1.2
"""m before the crossing point the planned robot is when the cart's centre crosses."""
CART_CLEARANCE = 0.2
"""m the cart keeps from the robot at its top speed (footprint to footprint, at least)."""
CORRIDOR_LENGTH = 3
"""Tiles of the one-tile corridor."""
STAND_FOR = 20.0
"""s the standing person stays in the corridor after the robot's planned arrival there: longer
than a navigator's patience for one recovery (the reference starts its ladder after about 1 s
without an admissible motion and aborts after 30 s without progress), shorter than a goal's
timeout; what a person finishing a phone call in a passage takes."""
DOORWAY_AHEAD = 0.2
"""m before level with the doorway a robot at its top speed is when the stepping person first
comes within REACTION_TIME's react_zone (1.05 m) of its footprint: the person is then about
80 degrees off its heading (ahead, in the front half-plane, and 60-120 degrees to its side,
its near edge too)."""
DOORWAY_OFF_LINE = 0.2
"""m: the straight line between the first two goals passes at most this far from the centres
of the route's straight stretch by the doorway (so the robot drives past it there)."""
DOORWAY_SEEN = 0.6
"""m of its one-tile step the person has walked when it is within react_zone of a robot
passing level with the doorway (1.4 m from the route's centre line, centre to centre)."""
ROW_TYPE = "table"
"""The catalogue type of the gap's row: 0.8 m along the row leaves a 0.2 m slot."""
CART_TYPE = "cart"
"""The catalogue type of the crossing cart."""
SIDES = ("left", "right")
"""The side of the robot's route (looking along it) a stressor's mover ends up beside."""
MOVER_KINDS = ("emerge", "crossing", "oncoming", "standing", "doorway")
"""The stressors with a mover (the gap has none)."""


def side_of(seed: int, ordinal: int) -> str:
    """The side for a suite's ``ordinal``-th mover room (0-based, in room order): the sides
    alternate, and the seed picks which comes first, so over seeds each kind meets the
    robot from each side."""
    return SIDES[(seed + ordinal) % 2]


@dataclass(frozen=True)
class Bodies:
    """What the timing needs of the robot and the cart, from the catalogue."""

    robot_half: tuple[float, float]
    """m, half the robot's footprint (length along its heading, width)."""
    top_speed: float
    """m/s, the robot's drive limit: no robot gets anywhere sooner than at this speed."""
    cart_half: tuple[float, float]
    """m, half the cart's footprint (length along its heading, width)."""

    @staticmethod
    def of(catalogue: Catalogue, robot_type: str) -> Bodies:
        robot = catalogue.types[robot_type]
        if robot.drive is None:
            raise ValueError(f"catalogue type '{robot_type}' has no drive")
        return Bodies(robot.footprint.half_extents(), robot.drive.max_linear,
                      catalogue.types[CART_TYPE].footprint.half_extents())


class StressorFailed(Exception):
    """This attempt's layout has no place for the stressor (the caller retries)."""


@dataclass(frozen=True)
class RowObject:
    """A static object the stressor puts down (the gap's row)."""

    type: str
    cell: Cell
    heading: float


@dataclass(frozen=True)
class MoverPath:
    """A mover's tiles before its timing is known: it waits on the first, walks the rest
    through ``vertices[anchor]`` (the meeting point) and stops on the last."""

    name: str
    role: str
    """'human' or 'dynamic'."""
    type: str
    vertices: tuple[Cell, ...]
    anchor: int
    lead: float
    heading: float = 0.0


@dataclass(frozen=True)
class TimedMover:
    name: str
    role: str
    type: str
    vertices: tuple[tuple[Cell, float], ...]
    """(tile, time in seconds) in walking order, the wait included."""
    heading: float
    behaviour: str
    """'yielding' for people; dynamic objects are scripted."""
    start_when: tuple[Cell, float] | None = None
    """(tile, metres): the trajectory starts when the robot's centre comes within that
    distance of the tile's centre (its vertex times count from then); None: with the run."""


@dataclass(frozen=True)
class StressorLayout:
    """What a stressor changes in a room, before the final route is known."""

    kind: str
    walls: frozenset[Cell]
    """Floors turned into walls (the corner stub, the corridor's sides)."""
    row: tuple[RowObject, ...]
    mover: MoverPath | None
    point: Cell
    """Where the encounter is planned: the meeting point, or the slot's first tile."""
    approach: tuple[Cell, ...]
    """Consecutive cells of the first leg the final route must still drive in this order
    (the straight approach to the meeting point, the corridor)."""
    keep_free: frozenset[Cell]
    """Tiles no other object may take: the first leg, the mover's tiles, the opening."""
    slot: tuple[Cell, Cell] | None = None
    """The gap's two tiles whose objects leave the slot between them."""
    slot_width: float = 0.0
    side: str = ""
    """The side of the route (SIDES) the mover ends up beside; '' for the gap."""


@dataclass(frozen=True)
class StressorPlan:
    """A stressor with its timing, as the room file gets it."""

    layout: StressorLayout
    mover: TimedMover | None
    arrival_s: float
    """Planned time the robot reaches ``layout.point`` (0 for the gap)."""
    meeting_s: float
    """Time the mover reaches the meeting point (0 for the gap)."""


def _sub(a: Cell, b: Cell) -> Cell:
    return (a[0] - b[0], a[1] - b[1])


def _add(a: Cell, b: Cell, k: int = 1) -> Cell:
    return (a[0] + k * b[0], a[1] + k * b[1])


def _left(d: Cell) -> Cell:
    """The unit step to the left of a route running along d (x east, y north)."""
    return (-d[1], d[0])


def side_cell(route_cell: Cell, d: Cell, beside: Cell) -> str:
    """Which side of a route running along d through ``route_cell`` the cell ``beside`` is
    on: 'left', 'right', or '' when it lies on the route's line."""
    left = _left(d)
    dot = (beside[0] - route_cell[0]) * left[0] + (beside[1] - route_cell[1]) * left[1]
    return "" if dot == 0 else ("left" if dot > 0 else "right")


def _perpendiculars(d: Cell, rng: random.Random, side: str | None = None,
                    flip: bool = False) -> list[Cell]:
    """The unit steps n across a route running along d: both in a random order, or with
    ``side`` the one pointing to that side (to the other side when ``flip``: a mover that
    comes from n and ends up on ``side``)."""
    left, right = _left(d), (d[1], -d[0])
    if side is None:
        sides = [left, right]
        rng.shuffle(sides)
        return sides
    if side not in SIDES:
        raise ValueError(side)
    return [left if (side == "left") != flip else right]


def _straight_runs(route: Sequence[Cell], before: int, after: int) -> list[tuple[int, Cell]]:
    """(k, d): route indices whose ``before`` cells before and ``after`` cells after lie on
    one axis-aligned straight line along d (unit step)."""
    out = []
    for k in range(before, len(route) - after):
        d = _sub(route[k], route[k - 1])
        if abs(d[0]) + abs(d[1]) != 1:
            continue
        if all(_sub(route[m], route[m - 1]) == d for m in range(k - before + 1, k + after + 1)):
            out.append((k, d))
    return out


def first_leg(floors: set[Cell], goals: Sequence[Cell]) -> list[Cell]:
    """The robot's route from its start to the second goal on the inflated floor graph."""
    leg = fast_route(floors, [goals[0], goals[1]])
    if leg is None:
        raise StressorFailed("the second goal is not reachable")
    return leg


def plan_layout(params: RoomParameters, floors: set[Cell], goals: Sequence[Cell],
                row_half_extent: float, rng: random.Random, side: str | None = None
                ) -> StressorLayout:
    """Where the stressor goes in this floor plan, its mover ending up on ``side`` of the
    route (one of SIDES; None: either); StressorFailed when nowhere fits."""
    leg = first_leg(floors, goals)
    kind = params.stressor
    if kind == "gap":
        return _gap(floors, goals, leg, row_half_extent, rng)
    blocked = set(goals) | set(leg)
    if kind == "emerge":
        return _emerge(floors, leg, blocked, rng, side)
    if kind == "crossing":
        return _crossing(floors, leg, blocked, rng, side)
    if kind == "oncoming":
        return _oncoming(floors, leg, blocked, rng, side)
    if kind == "standing":
        return _standing(floors, leg, blocked, rng, side)
    if kind == "doorway":
        return _doorway(floors, goals, leg, blocked, rng, side)
    raise ValueError(kind)


def _meeting_points(leg: list[Cell], rng: random.Random, side: str | None
                    ) -> Iterator[tuple[int, Cell, Cell, Cell]]:
    """(k, p, d, n) in a random order: a cell p = leg[k] that the route approaches straight
    along d for three cells and leaves along d, and the side n across the route there the
    mover comes from (it ends up on the other, ``side``)."""
    runs = _straight_runs(leg, 3, 1)
    rng.shuffle(runs)
    for k, d in runs:
        for n in _perpendiculars(d, rng, side, flip=True):
            yield k, leg[k], d, n


def _emerge(floors: set[Cell], leg: list[Cell], blocked: set[Cell], rng: random.Random,
            side: str | None) -> StressorLayout:
    for k, p, d, n in _meeting_points(leg, rng, side):
        stub, hide = _add(_sub(p, d), n), _add(p, n)
        toward = _sub(p, d)
        aside = _sub(toward, n)
        if any(t not in floors or t in blocked for t in (stub, hide, aside)):
            continue
        if not is_connected(floors - {stub}):
            continue
        mover = MoverPath("emerging_person", "human", "human", (hide, p, toward, aside),
                          anchor=1, lead=PERSON_LEAD)
        return StressorLayout("emerge", frozenset({stub}), (), mover, p,
                              tuple(leg[k - 3:k + 2]), frozenset(leg) | {hide, aside},
                              side=side_cell(toward, d, aside))
    raise StressorFailed("no straight stretch of the first leg with room for a wall stub "
                         "and a person behind it")


def _line_cells(a: Cell, b: Cell) -> set[Cell]:
    """The tiles the straight line between two tile centres passes through (sampled every
    tenth of a tile)."""
    steps = max(abs(b[0] - a[0]), abs(b[1] - a[1])) * 10
    return {(round(a[0] + (b[0] - a[0]) * m / steps), round(a[1] + (b[1] - a[1]) * m / steps))
            for m in range(steps + 1)} if steps else {a}


def _off_line(c: Cell, a: Cell, b: Cell) -> float:
    """Metres from the centre of tile c to the straight line through a and b."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    return abs(dx * (c[1] - a[1]) - dy * (c[0] - a[0])) / math.hypot(dx, dy)


def _doorway(floors: set[Cell], goals: Sequence[Cell], leg: list[Cell], blocked: set[Cell],
             rng: random.Random, side: str | None) -> StressorLayout:
    # The robot's real way is not the grid route: a navigator planning any-angle paths
    # drives the straight line between the goals where nothing is in its way. The doorway
    # goes where that line runs along the route's straight stretch, so the robot passes the
    # doorway's tile as the generator plans, whatever planner it has; the line's tiles are
    # kept free of objects.
    start, goal = goals[0], goals[1]
    line = _line_cells(start, goal)
    if not line <= floors:
        raise StressorFailed("the straight line between the first goals leaves the floor")
    runs = [(k, d) for k, d in _straight_runs(leg, 3, 1)
            if all(_off_line(leg[m], start, goal) <= DOORWAY_OFF_LINE
                   for m in range(k - 3, k + 2))]
    rng.shuffle(runs)
    for k, d in runs:
        p = leg[k]
        for n in _perpendiculars(d, rng, side):
            door, back = _add(p, n), _add(p, n, 2)
            if any(t not in floors or t in blocked for t in (door, back)):
                continue
            # Stubs either side of the doorway and of the tile behind it: the person is only
            # seen through the opening, from beside it.
            stubs = {_add(t, d, s) for t in (door, back) for s in (1, -1)} & floors
            if stubs & (blocked | line) or not is_connected(floors - stubs):
                continue
            mover = MoverPath("doorway_person", "human", "human", (back, door), anchor=1,
                              lead=0.0)
            return StressorLayout("doorway", frozenset(stubs), (), mover, p,
                                  tuple(leg[k - 3:k + 2]),
                                  frozenset(leg) | line | {door, back},
                                  side=side_cell(p, d, door))
    raise StressorFailed("no straight stretch of the first leg with two free tiles beside it "
                         "for a doorway")


def _crossing(floors: set[Cell], leg: list[Cell], blocked: set[Cell], rng: random.Random,
               side: str | None) -> StressorLayout:
    for k, p, d, n in _meeting_points(leg, rng, side):
        # Parked on the tile beside the route, where the robot passes it.
        way = [_add(p, n, 2), _add(p, n, 1), p, _add(p, n, -1)]
        if any(t not in floors or (t != p and t in blocked) for t in way):
            continue
        # The cart faces where it goes, so its length lies along its way.
        heading = float(round(math.degrees(math.atan2(-n[1], -n[0]))) % 360)
        mover = MoverPath("crossing_cart", "dynamic", CART_TYPE, tuple(way), anchor=2,
                          lead=CART_LEAD, heading=heading)
        return StressorLayout("crossing", frozenset(), (), mover, p,
                              tuple(leg[k - 3:k + 2]), frozenset(leg) | set(way),
                              side=side_cell(p, d, way[-1]))
    raise StressorFailed("no straight stretch of the first leg with two free tiles on "
                         "one side and one on the other for a crossing cart")


def _corridors(floors: set[Cell], leg: list[Cell], blocked: set[Cell], rng: random.Random,
               side: str | None) -> Iterator[tuple[int, Cell, list[Cell], Cell, frozenset[Cell]]]:
    """(a, n, corridor, aside, walls): one-tile corridors of ``CORRIDOR_LENGTH`` tiles on a
    straight stretch of the first leg from ``leg[a]`` (floors on both sides turned into
    ``walls``), with a free tile ``aside`` beside its near end on the side ``n`` points to;
    farthest from the start first."""
    length = CORRIDOR_LENGTH
    # One straight cell before the corridor and the corridor, whose far end (the person's
    # start) must not be the goal.
    runs = [(k, d) for k, d in _straight_runs(leg, 1, length - 1)
            if k + length - 1 < len(leg) - 1]
    # Farthest from the start first: the person must be out of the corridor before a robot
    # at top speed gets there, which a corridor near the start leaves no time for.
    runs.sort(key=lambda run: -run[0])
    for a, d in runs:
        corridor = leg[a:a + length]
        for n in _perpendiculars(d, rng, side):
            walls = {_add(c, n, s) for c in corridor for s in (1, -1)} & floors
            aside = _add(leg[a - 1], n)
            if aside not in floors or aside in blocked or walls & blocked:
                continue
            if not walls or not is_connected(floors - walls):
                continue
            yield a, n, corridor, aside, frozenset(walls)


def _oncoming(floors: set[Cell], leg: list[Cell], blocked: set[Cell], rng: random.Random,
              side: str | None) -> StressorLayout:
    for a, _, corridor, aside, walls in _corridors(floors, leg, blocked, rng, side):
        entrance = leg[a - 1]
        d = _sub(corridor[0], entrance)
        path = (*reversed(corridor), entrance, aside)
        mover = MoverPath("oncoming_person", "human", "human", path,
                          anchor=len(corridor) - 1, lead=ONCOMING_LEAD)
        return StressorLayout("oncoming", walls, (), mover, corridor[0],
                              tuple(leg[a - 1:a + len(corridor)]), frozenset(leg) | {aside},
                              side=side_cell(entrance, d, aside))
    raise StressorFailed(f"no straight stretch of {CORRIDOR_LENGTH + 1} tiles on the first "
                         f"leg for a one-tile corridor")


def _standing(floors: set[Cell], leg: list[Cell], blocked: set[Cell], rng: random.Random,
              side: str | None) -> StressorLayout:
    """A one-tile corridor that is the only way on (the walls across the room at its middle
    tile: a door in a wall), its person standing in that middle tile; it leaves by the far
    end and steps aside past it."""
    for a, n, corridor, _, walls in _corridors(floors, leg, blocked, rng, side):
        middle = corridor[len(corridor) // 2]
        across = set(walls)
        for way in (n, (-n[0], -n[1])):
            cell = _add(middle, way)
            while cell in floors:
                across.add(cell)
                cell = _add(cell, way)
        if across & blocked:
            continue
        rest = floors - across
        if not is_connected(rest) or is_connected(rest - {middle}):
            continue  # the door must be the only way on, and no floor cut off by the wall
        d = _sub(corridor[1], corridor[0])
        beyond = leg[a + len(corridor)]
        aside = _add(beyond, n)
        if aside not in rest or aside in blocked:
            continue
        path = (middle, *corridor[len(corridor) // 2 + 1:], beyond, aside)
        mover = MoverPath("standing_person", "human", "human", path, anchor=0, lead=0.0)
        return StressorLayout("standing", frozenset(across), (), mover, corridor[0],
                              tuple(leg[a - 1:a + len(corridor) + 1]),
                              frozenset(leg) | {aside}, side=side_cell(beyond, d, aside))
    raise StressorFailed("no straight stretch of the first leg where a wall across the room "
                         "leaves a one-tile corridor as the only way on")


def _gap(floors: set[Cell], goals: Sequence[Cell], leg: list[Cell], half: float,
         rng: random.Random) -> StressorLayout:
    start, goal = goals[0], goals[1]
    dx, dy = goal[0] - start[0], goal[1] - start[1]
    axis = 0 if abs(dx) >= abs(dy) else 1  # the leg's main axis; the row runs across it
    lat = 1 - axis
    span = goal[axis] - start[axis]
    step = 1 if span > 0 else -1
    positions = [start[axis] + step * m for m in range(2, abs(span) - 1)]
    rng.shuffle(positions)
    for c in positions:
        # Where the straight line between the goals crosses the row.
        at = start[lat] + (c - start[axis]) * (goal[lat] - start[lat]) / span
        low = math.floor(at)
        if at == low and rng.random() < 0.5:
            low -= 1

        def cell(a: int, b: int) -> Cell:
            return (a, b) if axis == 0 else (b, a)

        slot = (cell(c, low), cell(c, low + 1))
        if slot[0] not in floors or slot[1] not in floors:
            continue
        run = [slot[0], slot[1]]
        for direction in (1, -1):
            m = (low + 1) if direction == 1 else low
            while cell(c, m + direction) in floors:
                m += direction
                run.append(cell(c, m))
        run.sort()
        if any(t in goals for t in run):
            continue
        # The row's end tables leave a narrow gap to the wall too; next to the slot, that gap
        # can be a point's shorter way than the slot itself (seen in an L room's inner corner).
        if run[0] in slot or run[-1] in slot:
            continue
        openings = [t for t in run if min(abs(t[lat] - low), abs(t[lat] - low - 1)) >= 2
                    and _add(t, cell(1, 0)) in floors and _add(t, cell(-1, 0)) in floors]
        if not openings:
            continue
        far = max(abs(t[lat] - at) for t in openings)
        opening = rng.choice([t for t in openings if abs(t[lat] - at) == far])
        tables = [t for t in run if t != opening]
        rest = floors - set(tables)
        if not is_connected(rest):
            continue
        heading = 90.0 if axis == 0 else 0.0  # the table's long side along the row
        row = tuple(RowObject(ROW_TYPE, t, heading) for t in tables)
        # Free of other objects: the opening and the tiles either side of it (the way round
        # stays open), and the slot's and the straight line's tiles (the slot stays the
        # point's shortest way, with nothing else on the way to it).
        line = _line_cells(start, goal)
        keep = frozenset(t for t in line | {_add(u, cell(k, 0)) for u in (opening, *slot)
                                            for k in (-1, 0, 1)}
                         if t in floors) - set(tables)
        return StressorLayout("gap", frozenset(), row, None, slot[0], (), keep,
                              slot=slot, slot_width=round(1.0 - 2 * half, 6))
    raise StressorFailed("no place across the first leg for a row of tables with an opening "
                         "two tiles from the slot")


def route_lengths(route: Sequence[Cell]) -> list[float]:
    """Metres along ``route`` to each of its cells (tiles of 1 m)."""
    out = [0.0]
    for a, b in zip(route[:-1], route[1:], strict=True):
        out.append(out[-1] + math.dist(a, b))
    return out


def planned_arrival(route: Sequence[Cell], point: Cell, speed: float) -> float:
    """Seconds until the planned robot reaches ``point`` on ``route``."""
    return START_DELAY + route_lengths(route)[list(route).index(point)] / speed


def hold_times(go: float) -> list[float]:
    """The times of a mover's waiting vertices on its first tile when it sets off at ``go``
    s: HOLD_STEP apart at most, the last two SETTLE apart (also a search's shifted mover,
    generators/rooms/scenario.py)."""
    waiting = go - SETTLE
    intervals = math.ceil(waiting / HOLD_STEP - 1e-9)
    times = [round(k * waiting / intervals, 2) for k in range(intervals)]
    return [*times, round(waiting, 2), go]


def _time_doorway(layout: StressorLayout, mover: MoverPath, params: RoomParameters,
                  arrival: float, top: float) -> StressorPlan:
    """The doorway's step, started by the robot's position: within ``trigger`` of the tile
    level with the doorway, where a robot at its top speed (the nearest any robot can be
    when the person is seen) is DOORWAY_AHEAD before level when the person has walked
    DOORWAY_SEEN of its step. ``arrival_s`` and ``meeting_s`` are the planned robot's, for
    the reader: the run does not wait for them."""
    step = route_lengths(mover.vertices)[-1]
    walked = round(step / params.speed, 2)
    trigger = round(DOORWAY_AHEAD + top * DOORWAY_SEEN / params.speed, 2)
    timed = ((mover.vertices[0], 0.0), (mover.vertices[1], walked))
    person = TimedMover(mover.name, mover.role, mover.type, timed, mover.heading, "yielding",
                        (layout.point, trigger))
    nominal = min(NOMINAL_SPEED, top)
    meeting = arrival - trigger / nominal + walked
    return StressorPlan(replace(layout, mover=replace(mover, lead=trigger)), person,
                        round(arrival, 2), round(meeting, 2))


def time_layout(layout: StressorLayout, route: Sequence[Cell], params: RoomParameters,
                bodies: Bodies) -> StressorPlan:
    """The mover's vertex times from the final route; StressorFailed when the final route
    no longer meets the stressor where it was laid out, or the timing cannot be met."""
    if layout.kind == "gap":
        return StressorPlan(layout, None, 0.0, 0.0)
    mover = layout.mover
    assert mover is not None
    cells = list(route)
    first = layout.approach[0]
    at = cells.index(first) if first in cells else -1
    if at < 0 or cells[at:at + len(layout.approach)] != list(layout.approach):
        raise StressorFailed("the objects moved the robot's route off the stressor")
    final = cells[:at + len(layout.approach)]
    limit = params.max_speed if params.max_speed is not None else bodies.top_speed
    nominal, top = min(NOMINAL_SPEED, limit), min(bodies.top_speed, limit)
    arrival = planned_arrival(final, layout.point, nominal)
    if layout.kind == "doorway":
        return _time_doorway(layout, mover, params, arrival, top)
    meeting = arrival - mover.lead / nominal
    walk = route_lengths(mover.vertices)
    speed = params.speed
    # The standing person stands from the start until STAND_FOR past the robot's arrival.
    go = arrival + STAND_FOR if layout.kind == "standing" \
        else meeting - walk[mover.anchor] / speed
    if mover.role == "dynamic":
        # A scripted cart must have left the robot's lane before the robot, at its top
        # speed and on the straightest way, could be there.
        reach = math.dist(final[0], layout.point) - (bodies.robot_half[0]
                                                     + bodies.cart_half[1] + CART_CLEARANCE)
        lane = bodies.robot_half[1] + bodies.cart_half[0] + CART_CLEARANCE
        cleared = go + (walk[mover.anchor] + lane) / speed
        earliest = reach / top
        if cleared > earliest:
            go -= cleared - earliest
    if layout.kind == "oncoming":
        # Out of the corridor and aside, at its slowest (speed scale and a start delay of
        # up to one vertex interval, below HOLD_STEP), before a robot at top speed arrives.
        reach = math.dist(final[0], layout.approach[0]) - ONCOMING_CLEAR
        latest = HUMAN_SLOWEST * (reach / top - HOLD_STEP) - walk[-1] / speed
        go = min(go, latest)
    if go < MIN_WAIT:
        raise StressorFailed("the meeting point is too near the start to wait for the robot")
    go = round(go, 2)
    timed = [(mover.vertices[0], t) for t in hold_times(go)]
    timed += [(v, round(go + walk[m] / speed, 2)) for m, v in enumerate(mover.vertices)
              if m > 0]
    # The standing person is absorbed in a phone call: it gives way to nobody.
    behaviour = "yielding" if mover.role == "human" and layout.kind != "standing" \
        else "scripted"
    return StressorPlan(layout, TimedMover(mover.name, mover.role, mover.type, tuple(timed),
                                           mover.heading, behaviour),
                        round(arrival, 2), round(go + walk[mover.anchor] / speed, 2))
