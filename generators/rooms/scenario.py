"""A generated pair's continuous scenario parameters, beyond the room generator's factors:
when the humans start on their paths, when a stressor's mover sets off, and the sensor
faults the mission injects. `rei search` searches them as dimensions of the unit cube.

* ``phase`` (s): the time every generated human passes its first vertex. A human with an
  open path stands on its first tile until then; a looping human is already walking its
  loop and gets there at that time (its loop is shifted in time, its shape unchanged). The
  room file carries it as vertex times (``walker_1 ... at 4.2``) instead of a ``total``.
* ``stress_shift`` (s): the stressor's person sets off this much later (earlier when
  negative) than the generator timed it, so the encounter happens with the robot
  ``0.25 m/s x shift`` farther along its first leg (nearer the meeting point). The room
  file's mover times and its ``// stressor: meeting_s=`` carry it. A crossing cart is never
  delayed (it is timed to clear the robot's lane before a robot at top speed could be
  there); a shift that leaves a mover less than the generator's shortest wait is refused.
* ``object_shift``, ``goal_shift``, ``path_shift`` (m): continuous placement, each one
  number for the whole room (a per-element offset would add two dimensions per object and
  vertex, more than a search of a few hundred runs can learn; one signed distance per kind
  of element says what matters to a navigator: nearer the robot's way or farther from it).
  Every generated object (not a stressor's row) moves that far towards the nearest tile of
  the robot's planned route (away when negative); every goal but the first (the robot's
  start) towards the nearest wall or object; every generated human's trajectory vertex
  towards the nearest route tile. Each move is cut short where it would take the body off
  its own tile (an object's rotated footprint, the robot standing on a goal, a human's disc
  at a vertex), so nothing is moved into a wall, another object or the robot's start, and
  the pair is written with ``offset DX DY`` (grammars/common.tx). A human's curve may still
  graze something between vertices: the `rei-gen check` rules then refuse the candidate.
  The generator's descriptors (``// descriptors:``) are those of the layout before the move.
* ``KIND.PARAM`` (a fault kind of rei.lang.mission.faults and one of its parameters, e.g.
  ``laser_noise.sigma``): the mission gets a ``fault { }`` section with one entry per kind,
  active the whole run, its parameters set to the values chosen.

Each value is a ``LOW:HIGH`` range checked against the parameter's own limits (the fault
kinds' limits are the mission language's). The pair is written again and checked with the
`rei-gen check` rules by the caller. This module never touches files or random state.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import replace

from rei.catalogue import Catalogue, ObjectType
from rei.generators.rooms.construct import (
    ROBOT_TYPE,
    ROW_PREFIX,
    CatalogueFacts,
    PlacedObjectPlan,
    RoomPlan,
)
from rei.generators.rooms.descriptors import format_number
from rei.generators.rooms.geometry import Cell
from rei.generators.rooms.space import Interval, ParameterError, parse_range
from rei.generators.rooms.stressors import MIN_WAIT, TimedMover, hold_times
from rei.lang.mission.faults import KINDS
from rei.lang.room.checks import rotated_half_extents

PHASE = "phase"
STRESS_SHIFT = "stress_shift"
MAX_PHASE = 600.0
"""s: the latest start phase (a generated mission lasts minutes)."""
MAX_SHIFT = 60.0
"""s: the largest stressor shift either way."""
OBJECT_SHIFT = "object_shift"
GOAL_SHIFT = "goal_shift"
PATH_SHIFT = "path_shift"
PLACEMENT_SHIFTS = (OBJECT_SHIFT, GOAL_SHIFT, PATH_SHIFT)
TILE = 1.0
"""m: the generator's tile (writer.room_text writes ``tile 1.0``)."""
MAX_PLACEMENT = TILE / 2
"""m: the largest placement shift either way; a body never leaves its tile anyway."""


class ScenarioRefused(Exception):
    """These values cannot be put into this room (a candidate the search cannot build)."""


def fault_parameter(name: str) -> tuple[str, str] | None:
    """``KIND.PARAM`` -> (kind, parameter), or None for a name that is not a fault's."""
    kind, dot, param = name.partition(".")
    return (kind, param) if dot else None


def parse_scenario(name: str, text: str) -> Interval:
    """The range of one scenario parameter (an Interval called ``name``), checked;
    ParameterError names the option."""
    if name == PHASE:
        return parse_range("phase", name, text, 0.0, MAX_PHASE, False)
    if name == STRESS_SHIFT:
        return parse_range("stress-shift", name, text, -MAX_SHIFT, MAX_SHIFT, False)
    if name in PLACEMENT_SHIFTS:
        return parse_range(name.replace("_", "-"), name, text, -MAX_PLACEMENT, MAX_PLACEMENT,
                           False)
    option = "fault-range"
    pair = fault_parameter(name)
    if pair is None:
        raise ParameterError(option, "KIND.PARAM=LOW:HIGH (e.g. laser_noise.sigma=0.01:0.1)",
                             f"'{name}={text}'")
    kind, param = pair
    spec = KINDS.get(kind)
    if spec is None:
        raise ParameterError(option, f"a fault kind ({', '.join(KINDS)})", f"'{kind}'")
    parameter = spec.parameter(param)
    if parameter is None:
        names = ", ".join(p.name for p in spec.parameters) or "none"
        raise ParameterError(option, f"a parameter of {kind} ({names})", f"'{param}'")
    return parse_range(option, name, text, parameter.low, parameter.high, parameter.low_open)


def check_faults(ranges: Sequence[Interval]) -> None:
    """Refuse fault kinds whose required parameters are not all searched (a fault entry
    with a parameter missing is not a mission), before any candidate is built."""
    searched: dict[str, set[str]] = {}
    for r in ranges:
        pair = fault_parameter(r.factor)
        if pair is not None:
            searched.setdefault(pair[0], set()).add(pair[1])
    for kind, params in searched.items():
        missing = [p.name for p in KINDS[kind].parameters
                   if p.default is None and p.name not in params]
        if missing:
            raise ParameterError("fault-range", f"a range for every required parameter of "
                                                f"{kind} (also {', '.join(missing)})",
                                 f"only {', '.join(sorted(params))}")


def apply_to_plan(plan: RoomPlan, values: Mapping[str, float],
                  catalogue: Catalogue | None = None) -> RoomPlan:
    """The plan with the humans' phase, the stressor's shift and the placement shifts put
    in; ScenarioRefused when this room cannot take them. ``catalogue`` (the bodies' sizes)
    is needed for the placement shifts."""
    if any(name in values for name in PLACEMENT_SHIFTS):
        if catalogue is None:
            raise ValueError("placement shifts need the catalogue's footprints")
        plan = placed(plan, values, catalogue)
    if PHASE in values:
        plan = replace(plan, humans=tuple(replace(h, start_s=values[PHASE])
                                          for h in plan.humans))
    shift = values.get(STRESS_SHIFT, 0.0)
    if STRESS_SHIFT in values and shift != 0.0:
        stress = plan.stressor
        if stress is None or stress.mover is None:
            raise ScenarioRefused("--stress-shift: expected a room with a stressor's mover "
                                  "(--stressor emerge, oncoming or crossing), found none")
        if stress.mover.role != "human" and shift > 0:
            raise ScenarioRefused("--stress-shift: a crossing cart is timed to clear the "
                                  "robot's lane first and cannot set off later; expected a "
                                  f"shift of at most 0 s, found {shift:g} s")
        plan = replace(plan, stressor=replace(stress, mover=shifted(stress.mover, shift),
                                              meeting_s=round(stress.meeting_s + shift, 3)))
    return plan


def shifted(mover: TimedMover, shift: float) -> TimedMover:
    """The mover setting off ``shift`` seconds later, its wait written as the generator
    writes it (``hold_times``)."""
    first = mover.vertices[0][0]
    hold = [t for c, t in mover.vertices if c == first]
    go = round(hold[-1] + shift, 3)  # the shift has 3 decimals: keep them all
    if go < MIN_WAIT:
        raise ScenarioRefused(f"--stress-shift: the mover would wait {go:g} s; expected at "
                              f"least {MIN_WAIT:g} s (a shift of at least "
                              f"{MIN_WAIT - hold[-1]:g} s here)")
    walk = [(c, round(t + shift, 3)) for c, t in mover.vertices[len(hold):]]
    return replace(mover, vertices=(*((first, t) for t in hold_times(go)), *walk))


def placed(plan: RoomPlan, values: Mapping[str, float], catalogue: Catalogue) -> RoomPlan:
    """The plan with ``object_shift``, ``goal_shift`` and ``path_shift`` among ``values``
    put in as offsets (see the module's docstring)."""
    route = tuple(dict.fromkeys(plan.route))
    if OBJECT_SHIFT in values:
        shift = values[OBJECT_SHIFT]

        def moved(o: PlacedObjectPlan) -> PlacedObjectPlan:
            if o.name.startswith(ROW_PREFIX):
                return o
            room_x, room_y = object_room(catalogue.types[o.type], o.heading)
            return replace(o, offset=towards(o.cell, route, shift, room_x, room_y))
        plan = replace(plan, objects=tuple(moved(o) for o in plan.objects))
    if GOAL_SHIFT in values and len(plan.goals) > 1:
        radius = catalogue.types[ROBOT_TYPE].footprint.circumradius()
        room = TILE / 2 - radius
        standing = {o.cell for o in plan.objects}
        blocked = tuple(sorted(c for c in _around(plan.goals)
                               if c not in plan.floors or c in standing))
        plan = replace(plan, goal_offsets=((0.0, 0.0), *(
            towards(g, blocked, values[GOAL_SHIFT], room, room) for g in plan.goals[1:])))
    if PATH_SHIFT in values and plan.humans:
        shift = values[PATH_SHIFT]
        room = TILE / 2 - max(catalogue.types["human"].footprint.half_extents())
        plan = replace(plan, humans=tuple(
            replace(h, offsets=tuple(towards(v, route, shift, room, room) for v in h.vertices))
            for h in plan.humans))
    return plan


def object_room(otype: ObjectType, heading: float, tile: float = TILE) -> tuple[float, float]:
    """How far (m) an object of this type turned ``heading`` degrees can move from its tile's
    centre along x and along y and keep its footprint on the tile (OFFSET-TILE): (tile - its
    extent) / 2 on each axis. A table or a shelf nearly fills a 1 m tile, so an object shift
    moves it little whatever the range asked for (docs/search.md lists every kind)."""
    hx, hy = rotated_half_extents(otype, heading)
    return tile / 2 - hx, tile / 2 - hy


def object_rooms(catalogue: Catalogue, tile: float = TILE
                 ) -> dict[str, dict[float, tuple[float, float]]]:
    """``object_room`` of every static kind at every heading the generator places it at."""
    facts = CatalogueFacts.of(catalogue, tile)
    return {name: {h: object_room(otype, h, tile) for h in facts.headings[name]}
            for name, otype in facts.types.items()}


def _around(cells: Sequence[Cell], reach: int = 3) -> set[Cell]:
    return {(i + di, j + dj) for i, j in cells
            for di in range(-reach, reach + 1) for dj in range(-reach, reach + 1)}


def towards(cell: Cell, targets: Sequence[Cell], shift: float, room_x: float,
            room_y: float) -> tuple[float, float]:
    """The offset (m) moving a thing on ``cell`` ``shift`` metres towards the nearest of
    ``targets`` (away when negative; the first in order when several are as near), cut
    short so it moves at most ``room_x`` / ``room_y`` either way; rounded towards the
    tile's centre to the millimetre, so the bytes are the same everywhere. (0, 0) when
    there is no target or the thing is on one."""
    if not targets or shift == 0.0:
        return (0.0, 0.0)
    target = min(targets, key=lambda t: math.dist(t, cell))
    gap = math.dist(target, cell)
    if gap == 0.0:
        return (0.0, 0.0)
    ux, uy = (target[0] - cell[0]) / gap, (target[1] - cell[1]) / gap
    step = abs(shift)
    for u, room in ((ux, room_x), (uy, room_y)):
        if abs(u) > 1e-12:
            step = min(step, max(room, 0.0) / abs(u))
    sign = 1.0 if shift > 0 else -1.0
    return (_mm(sign * step * ux), _mm(sign * step * uy))


def _mm(value: float) -> float:
    """Metres truncated to whole millimetres (towards 0: never past the room allowed)."""
    return math.trunc(round(value * 1000.0, 6)) / 1000.0 + 0.0


def fault_section(values: Mapping[str, float]) -> list[str]:
    """The mission's ``fault { }`` lines for the fault parameters among ``values``."""
    entries: dict[str, list[str]] = {}
    for name in sorted(values):
        pair = fault_parameter(name)
        if pair is not None:
            entries.setdefault(pair[0], []).append(f"{pair[1]} {format_number(values[name])}")
    if not entries:
        return []
    return (["    fault {"] + [f"        {kind} {' '.join(params)}"
                               for kind, params in entries.items()] + ["    }"])


def with_faults(mission: str, values: Mapping[str, float]) -> str:
    """The mission text with its fault section before the first goal."""
    lines = fault_section(values)
    if not lines:
        return mission
    out = mission.splitlines()
    at = next(k for k, line in enumerate(out) if line.startswith("    goal "))
    return "\n".join([*out[:at], *lines, *out[at:]]) + "\n"


def comment(values: Mapping[str, float]) -> str:
    """The room file's ``// scenario:`` line (read back by ``read_metadata``)."""
    return "// scenario: " + " ".join(f"{k}={format_number(v)}" for k, v in sorted(values.items()))


__all__ = ["GOAL_SHIFT", "MAX_PHASE", "MAX_PLACEMENT", "MAX_SHIFT", "OBJECT_SHIFT",
           "PATH_SHIFT", "PHASE", "PLACEMENT_SHIFTS", "STRESS_SHIFT",
           "ScenarioRefused", "apply_to_plan", "check_faults", "comment",
           "fault_section", "object_room", "object_rooms", "parse_scenario", "placed",
           "towards", "with_faults"]
