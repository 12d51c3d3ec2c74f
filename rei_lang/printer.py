"""Writing models back as REI text: the inverse of parsing, for roundtrip tests and tools.

A room is printed in the long form (explicit floors and walls with their links as written,
grid cells included), so printing never depends on how the file was first written (a grid's
corner walls, which touch no floor, have no long form and are left out); a
mission is printed as written. Numbers are printed with repr, so they read back exactly.
"""

from __future__ import annotations

from rei.lang.mission.model import (
    COLLECTED_DATA,
    DEFAULT_HEADING_TOLERANCE,
    DEFAULT_SAMPLE_RATE,
    DEFAULT_SETTLE,
    DEFAULT_TOLERANCE,
    Mission,
)
from rei.lang.room.model import DEFAULT_TILE_SIZE, PlacedObject, Room

_KEYWORD = {"static": "object", "dynamic": "dynamic", "human": "human", "robot": "robot"}


def _num(value: float) -> str:
    return repr(float(value))


def _offset(offset: tuple[float, float]) -> str:
    return f" offset {_num(offset[0])} {_num(offset[1])}" if offset != (0.0, 0.0) else ""


def _object_line(obj: PlacedObject) -> list[str]:
    head = f"    {_KEYWORD[obj.role]} {obj.name}"
    if obj.role != "human" or obj.type != "human":
        head += f" : {obj.type}"
    head += f" on {obj.floor.name}" + _offset(obj.offset)
    if obj.heading_deg is not None:
        head += f" heading {_num(obj.heading_deg)}"
    traj = obj.trajectory
    if traj is None:
        return [head]
    options = ""
    if traj.total_time is not None:
        options += f" total {_num(traj.total_time)}"
    options += " loop" if traj.loop else ""
    if traj.trigger is not None:
        options += (f" when robot within {_num(traj.trigger.distance)} of "
                    f"{traj.trigger.floor.name}")
    lines = [head + f" trajectory{options} {{"]
    for vertex in traj.vertices:
        at = f" at {_num(vertex.time)}" if vertex.time is not None else ""
        lines.append(f"        {vertex.floor.name}{_offset(vertex.offset)}{at}")
    lines.append("    }")
    return lines


def print_room(room: Room, catalogue: str | None = None) -> str:
    """The room as .room text; ``catalogue`` is the path to write for a catalogue setting."""
    lines = [f"room {room.name} {{"]
    if room.tile_size != DEFAULT_TILE_SIZE:
        lines.append(f"    tile {_num(room.tile_size)}")
    if catalogue is not None:
        lines.append(f'    catalogue "{catalogue}"')
    for floor in room.floors.values():
        type_part = f" : {floor.type}" if floor.type != "floor_tile" else ""
        links = " ".join(f"{side.keyword} {ref.name}" for side, ref in floor.links)
        lines.append(f"    floor {floor.name}{type_part}" + (f" {{ {links} }}" if links else ""))
    named = {target for links in room.neighbours.values() for target in links.values()}
    for wall in room.walls.values():
        if wall.name not in named:
            continue  # a grid's corner wall: placed by the grid, not expressible as a link
        type_part = f" : {wall.type}" if wall.type != "wall" else ""
        lines.append(f"    wall {wall.name}{type_part}")
    for obj in room.objects:
        lines.extend(_object_line(obj))
    lines.append("}")
    return "\n".join(lines) + "\n"


def print_mission(mission: Mission, room_path: str) -> str:
    lines = [f'mission {mission.name} in "{room_path}" {{']
    if mission.cycles != 1:
        lines.append(f"    cycles {mission.cycles}")
    if mission.time_limit is not None:
        lines.append(f"    time_limit {_num(mission.time_limit)}")
    if mission.max_speed is not None:
        lines.append(f"    max_speed {_num(mission.max_speed)}")
    if mission.settle != DEFAULT_SETTLE:
        lines.append(f"    settle {_num(mission.settle)}")
    if mission.sample_rate != DEFAULT_SAMPLE_RATE or mission.data != COLLECTED_DATA:
        lines.append(f"    monitor {{ rate {_num(mission.sample_rate)} Hz  data "
                     f"{', '.join(mission.data)} }}")
    if mission.faults:
        lines.append("    fault {")
        lines.extend(f"        {fault.text()}" for fault in mission.faults)
        lines.append("    }")
    for goal in mission.goals:
        line = f"    goal {goal.name} at {goal.floor.name}{_offset(goal.offset)}"
        if goal.tolerance != DEFAULT_TOLERANCE:
            line += f" tolerance {_num(goal.tolerance)}"
        if goal.heading_deg is not None:
            line += f" heading {_num(goal.heading_deg)}"
        if goal.heading_tolerance_deg != DEFAULT_HEADING_TOLERANCE:
            line += f" heading_tolerance {_num(goal.heading_tolerance_deg)}"
        line += f" timeout {_num(goal.timeout)}"
        lines.append(line)
    lines.append("}")
    return "\n".join(lines) + "\n"
