"""Building the concrete model from checked documents; refuses documents with errors."""

from __future__ import annotations

import math
from pathlib import Path

from rei.catalogue import Catalogue
from rei.generators.concrete.model import (
    ConcreteBlock,
    ConcreteGoal,
    ConcreteMission,
    ConcreteObject,
    ConcreteWorld,
    Pose2D,
    StartWhen,
    TimedPoint,
    TimedTrajectory,
)
from rei.lang.errors import LanguageError
from rei.lang.mission.document import MissionDocument
from rei.lang.room.document import RoomDocument
from rei.lang.room.model import Room, Trajectory
from rei.lang.room.spline import vertex_times
from rei.lang.workspace import Workspace, load_mission


def _xy(cell: tuple[int, int], tile: float,
        offset: tuple[float, float] = (0.0, 0.0)) -> tuple[float, float]:
    """A floor's centre in metres, moved by an ``offset`` written in the file."""
    return cell[0] * tile + offset[0], cell[1] * tile + offset[1]


def _timed(traj: Trajectory, room: Room, cells: dict[str, tuple[int, int]]) -> TimedTrajectory:
    pts = [_xy(cells[v.floor.name], room.tile_size, v.offset) for v in traj.vertices]
    times, pts = vertex_times(pts, [v.time for v in traj.vertices], traj.total_time, traj.loop)
    points = tuple(TimedPoint(t, x, y) for t, (x, y) in zip(times, pts, strict=True))
    start_when = None
    if traj.trigger is not None:
        name = traj.trigger.floor.name
        start_when = StartWhen(name, *_xy(cells[name], room.tile_size), traj.trigger.distance)
    return TimedTrajectory(points, traj.loop, start_when)


def concretise_room(doc: RoomDocument) -> ConcreteWorld:
    if not doc.ok or doc.room is None or doc.layout is None or doc.catalogue is None:
        raise LanguageError([d for d in doc.diagnostics if d.is_error])
    room, layout, catalogue = doc.room, doc.layout, doc.catalogue
    cells = dict(layout.cells)
    tile = room.tile_size

    def block(name: str, kind: str, type_name: str) -> ConcreteBlock:
        x, y = _xy(cells[name], tile)
        return ConcreteBlock(name, kind, _type(catalogue, type_name), cells[name], x, y,  # type: ignore[arg-type]
                             tile)

    floors = tuple(block(f.name, "floor", f.type) for f in room.floors.values())
    walls = tuple(block(w.name, "wall", w.type) for w in room.walls.values())
    objects: list[ConcreteObject] = []
    robot: ConcreteObject | None = None
    for obj in room.objects:
        x, y = _xy(cells[obj.floor.name], tile, obj.offset)
        pose = Pose2D(x, y, math.radians(obj.heading_deg or 0.0))
        trajectory = _timed(obj.trajectory, room, cells) if obj.trajectory is not None else None
        concrete = ConcreteObject(obj.name, obj.role, _type(catalogue, obj.type), obj.floor.name,
                                  pose, trajectory, obj.behaviour)
        if obj.role == "robot":
            robot = concrete
        else:
            objects.append(concrete)
    assert robot is not None  # a valid room has exactly one robot
    return ConcreteWorld(room.name, room.path, tile, floors, walls, tuple(objects), robot)


def _type(catalogue: Catalogue, name: str):  # type: ignore[no-untyped-def]
    otype = catalogue.get(name)
    assert otype is not None  # checked by the room's CATALOGUE-TYPE rule
    return otype


def concretise_mission(doc: MissionDocument) -> ConcreteMission:
    if not doc.ok or doc.mission is None or doc.room is None:
        raise LanguageError([d for d in doc.diagnostics if d.is_error])
    world = concretise_room(doc.room)
    mission = doc.mission
    goals = []
    for goal in mission.goals:
        floor = world.floor(goal.floor.name)
        yaw = math.radians(goal.heading_deg) if goal.heading_deg is not None else None
        goals.append(ConcreteGoal(goal.name, floor.name, floor.x + goal.offset[0],
                                  floor.y + goal.offset[1], yaw, goal.tolerance,
                                  goal.timeout, math.radians(goal.heading_tolerance_deg)))
    return ConcreteMission(mission.name, mission.path, world, tuple(goals), mission.cycles,
                           mission.effective_time_limit(), mission.max_speed,
                           mission.sample_rate, mission.data, mission.faults, mission.settle)


def load_concrete_mission(path: str | Path, workspace: Workspace | None = None) -> ConcreteMission:
    """Check a .mission file (and its room) and map it to metres; LanguageError if invalid."""
    return concretise_mission(load_mission(path, workspace))
