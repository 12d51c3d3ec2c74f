"""From a parsed .mission to the typed Mission, checked against its room.

Rules: the imported room exists and is valid, each goal names a floor of that room that
the robot can reach, at least two goals (thesis 4.1.2: start and final place), unique goal
names, options given once, and every number finite and in range. The optional ``monitor``
block names known data (each once, ground truth among them) and a sampling rate in range.
The optional ``fault`` section names known fault kinds with known, finite, in-range
parameters, each fault once (rei.lang.mission.faults).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from rei.lang.errors import Diagnostic, Span
from rei.lang.mission.faults import FaultDefinition, link_fault_section
from rei.lang.mission.model import (
    COLLECTED_DATA,
    DEFAULT_HEADING_TOLERANCE,
    DEFAULT_SAMPLE_RATE,
    DEFAULT_SETTLE,
    DEFAULT_TIMEOUT,
    DEFAULT_TOLERANCE,
    MAX_SAMPLE_RATE,
    REQUIRED_DATA,
    Goal,
    Mission,
)
from rei.lang.numbers import NO_OFFSET, read_number, read_offset
from rei.lang.parsing import span_of
from rei.lang.room.checks import offset_problem, passable_floors
from rei.lang.room.document import RoomDocument
from rei.lang.room.linker import MAX_TIME
from rei.lang.room.model import NameRef
from rei.lang.source import SourceText
from rei.lang.suggest import did_you_mean

MAX_CYCLES = 10_000
_WORDS = {"FaultSection": "fault", "TimeLimit": "time_limit", "MaxSpeed": "max_speed",
          "Settle": "settle"}


def room_path_of(textx_mission: Any, source: SourceText) -> str:
    written = textx_mission.room.path
    # An empty name must not become the mission's folder (read as "a folder").
    return str(Path(source.path).parent / written) if written else ""


def link_mission(textx_mission: Any, source: SourceText, room_doc: RoomDocument
                 ) -> tuple[Mission, list[Diagnostic]]:
    diagnostics: list[Diagnostic] = []

    def span(obj: Any) -> Span:
        return span_of(obj, source)

    def number(text: str, obj: Any, what: str, **bounds: Any) -> float | None:
        return read_number(text, span(obj), what, diagnostics, **bounds)

    cycles: float | None = None
    time_limit: float | None = None
    max_speed: float | None = None
    settle: float | None = None
    sample_rate: float | None = None
    data: tuple[str, ...] = COLLECTED_DATA
    seen: set[str] = set()
    goals: list[Goal] = []
    goal_names: dict[str, Span] = {}
    faults: list[FaultDefinition] = []
    fault_names: dict[str, Span] = {}
    for item in textx_mission.items:
        kind = type(item).__name__
        if kind != "Goal":
            if kind in seen:
                word = _WORDS.get(kind, kind.lower())
                diagnostics.append(Diagnostic(span(item), "OPTION-REPEAT",
                                              f"expected one '{word}' setting, found another"))
                continue
            seen.add(kind)
        if kind == "Cycles":
            cycles = number(item.count, item, "cycles", low=1, high=MAX_CYCLES, integer=True)
        elif kind == "TimeLimit":
            time_limit = number(item.seconds, item, "time_limit (seconds)", low=0.0,
                                high=MAX_TIME, low_open=True)
        elif kind == "Settle":
            settle = number(item.seconds, item, "settle (seconds)", low=0.0, high=MAX_TIME)
        elif kind == "MaxSpeed":
            max_speed = number(item.value, item, "max_speed (m/s)", low=0.0, high=100.0,
                               low_open=True)
        elif kind == "Monitor":
            sample_rate, data = _monitor(item, span, number, diagnostics)
        elif kind == "FaultSection":
            faults.extend(link_fault_section(item, span, diagnostics, fault_names))
        else:
            goals.append(_goal(item, len(goals) + 1, span, number, diagnostics, goal_names))

    mission = Mission(
        name=textx_mission.name,
        path=source.path,
        span=span(textx_mission),
        room_path=room_path_of(textx_mission, source),
        room_span=span(textx_mission.room),
        cycles=int(cycles) if cycles is not None else 1,
        time_limit=time_limit,
        max_speed=max_speed,
        goals=tuple(goals),
        sample_rate=sample_rate if sample_rate is not None else DEFAULT_SAMPLE_RATE,
        data=data,
        faults=tuple(faults),
        settle=settle if settle is not None else DEFAULT_SETTLE,
    )
    if len(goals) < 2:
        diagnostics.append(Diagnostic(mission.span, "MISSION-GOALS",
                                      f"mission '{mission.name}': expected at least two goals "
                                      f"(start and final place), found {len(goals)}"))
    diagnostics.extend(_check_against_room(mission, room_doc))
    return mission, diagnostics


def _monitor(item: Any, span: Any, number: Any, diagnostics: list[Diagnostic]
             ) -> tuple[float | None, tuple[str, ...]]:
    """The ``monitor`` block: (sampling rate or None, the collected data in COLLECTED_DATA's
    order); every data name known and given once, the required ones present."""
    rate: float | None = None
    data: tuple[str, ...] = COLLECTED_DATA
    given: set[str] = set()
    for setting in item.settings:
        kind = type(setting).__name__
        word = "rate" if kind == "SampleRate" else "data"
        if kind in given:
            diagnostics.append(Diagnostic(span(setting), "OPTION-REPEAT",
                                          f"monitor: expected one '{word}', found another"))
            continue
        given.add(kind)
        if kind == "SampleRate":
            rate = number(setting.hz, setting, "monitor rate (samples per second)", low=0.0,
                          high=MAX_SAMPLE_RATE, low_open=True)
            continue
        named: dict[str, Span] = {}
        for entry in setting.names:
            name, where = entry.name, span(entry)
            if name not in COLLECTED_DATA:
                diagnostics.append(Diagnostic(where, "MONITOR-DATA",
                                              f"monitor data: expected one of "
                                              f"{', '.join(COLLECTED_DATA)}, found '{name}'"
                                              + did_you_mean(name, COLLECTED_DATA)))
            elif name in named:
                diagnostics.append(Diagnostic(where, "MONITOR-DATA",
                                              f"monitor data: expected each name once, found "
                                              f"'{name}' again (first at line "
                                              f"{named[name].line})"))
            else:
                named[name] = where
        for required in REQUIRED_DATA:
            if required not in named:
                diagnostics.append(Diagnostic(span(setting), "MONITOR-DATA",
                                              f"monitor data: expected '{required}' among the "
                                              f"collected data (every sample is built around "
                                              f"the bodies' poses), found "
                                              f"{', '.join(e.name for e in setting.names)}"))
        data = tuple(d for d in COLLECTED_DATA if d in named)
    return rate, data


def _goal(item: Any, index: int, span: Any, number: Any, diagnostics: list[Diagnostic],
          names: dict[str, Span]) -> Goal:
    name = item.name or f"goal_{index}"
    goal_span = span(item)
    if name in names:
        diagnostics.append(Diagnostic(goal_span, "NAME-UNIQUE",
                                      f"expected a unique goal name, found '{name}' again (first "
                                      f"at line {names[name].line})"))
    names.setdefault(name, goal_span)
    tolerance = heading = heading_tolerance = timeout = None
    given: set[str] = set()
    for option in item.options:
        kind = type(option).__name__
        if kind in given:
            diagnostics.append(Diagnostic(span(option), "OPTION-REPEAT",
                                          f"goal '{name}': expected one '{kind.lower()}', found "
                                          f"another"))
            continue
        given.add(kind)
        if kind == "Tolerance":
            tolerance = number(option.metres, option, f"tolerance of goal '{name}' (metres)",
                               low=0.0, high=100.0, low_open=True)
        elif kind == "HeadingTolerance":
            heading_tolerance = number(option.degrees, option,
                                       f"heading_tolerance of goal '{name}' (degrees)",
                                       low=0.0, high=180.0, low_open=True)
        elif kind == "GoalHeading":
            heading = number(option.degrees, option, f"heading of goal '{name}' (degrees)",
                             low=-360.0, high=360.0)
        else:
            timeout = number(option.seconds, option, f"timeout of goal '{name}' (seconds)",
                             low=0.0, high=MAX_TIME, low_open=True)
    offset = NO_OFFSET if item.offset is None else read_offset(
        item.offset.dx, item.offset.dy, span(item.offset), f"offset of goal '{name}'",
        diagnostics)
    return Goal(name, NameRef(item.floor.name, span(item.floor)),
                tolerance if tolerance is not None else DEFAULT_TOLERANCE, heading,
                timeout if timeout is not None else DEFAULT_TIMEOUT, goal_span,
                heading_tolerance if heading_tolerance is not None
                else DEFAULT_HEADING_TOLERANCE, offset)


def _check_against_room(mission: Mission, room_doc: RoomDocument) -> list[Diagnostic]:
    out: list[Diagnostic] = []
    if room_doc.room is None or not room_doc.ok:
        errors = [d for d in room_doc.diagnostics if d.is_error]
        first = errors[0] if errors else None
        if first is not None and first.rule.startswith("INPUT-"):
            # The file could not be read as text at all: say why, in its own words.
            if "expected" not in first.message:  # "no such file", "cannot read the file: …"
                message = f"expected a room file at '{mission.room_path}', found {first.message}"
            else:
                message = (f"room '{mission.room_path}': {first.message}" if mission.room_path
                           else first.message)
        else:
            # A syntax error's message quotes the file; a file that is not a room (imported
            # by mistake) must not have its contents echoed, so only say where it is.
            shown = ("" if first is None else f"; first: {first.span.file}:{first.span.line}:"
                     f"{first.span.col}: {first.rule}" + (
                         "" if first.rule.startswith("SYNTAX") else f": {first.message}"))
            message = (f"expected a valid room, found {len(errors)} problem(s) in "
                       f"'{mission.room_path}'" + shown)
        out.append(Diagnostic(mission.room_span, "MISSION-ROOM", message))
        if room_doc.room is None:
            return out
    room = room_doc.room
    reachable = (passable_floors(room, room_doc.layout) if room_doc.layout is not None
                 else set())
    for goal in mission.goals:
        name = goal.floor.name
        if name in room.floors:
            problem = offset_problem(goal.offset, room.tile_size, 0.0)
            if problem:
                out.append(Diagnostic(goal.span, "OFFSET-TILE",
                                      f"goal '{goal.name}': expected {problem}"))
            if room_doc.ok and name not in reachable:
                blockers = [o.name for o in room.objects_on(name)
                            if o.role in ("static", "dynamic")]
                why = (f"'{blockers[0]}' stands on it" if blockers
                       else "no free path from the robot's floor leads there")
                out.append(Diagnostic(goal.floor.span, "GOAL-UNREACHABLE",
                                      f"goal '{goal.name}': expected a floor the robot can "
                                      f"reach, found '{name}': {why}"))
        elif name in room.walls:
            out.append(Diagnostic(goal.floor.span, "REF-KIND",
                                  f"goal '{goal.name}': expected a floor, found the wall "
                                  f"'{name}'"))
        else:
            out.append(Diagnostic(goal.floor.span, "REF-UNRESOLVED",
                                  f"goal '{goal.name}': expected a floor of room "
                                  f"'{room.name}', found '{name}'"
                                  + did_you_mean(name, room.floors)))
    return out
