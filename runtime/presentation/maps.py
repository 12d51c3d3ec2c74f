"""Maps of runs from above, shared by the campaign report and the page of one run: the room
as the generators drew it (rei.generators.picture), with what the trace says happened on top
(the robot's path, the humans' paths, where signals fired).

A run folder keeps the generated world (world/world.json), not the .mission it came from;
``world_from_manifest`` turns that manifest back into the concrete world the picture code
draws, so a run's map shows exactly the world that ran even when the .mission file has moved
or changed since. This module must never write files or choose a global backend.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, cast

import numpy as np

from rei.catalogue import ObjectType, Tile, default_catalogue
from rei.catalogue.model import Kind
from rei.runtime.observation.run_folder import Paths, SignalEvent
from rei.runtime.presentation.figures import TEXT_PT, new_figure

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from rei.generators.concrete import ConcreteMission, ConcreteWorld
    from rei.runtime.artifacts.world import BodySpec, WorldManifest
    from rei.runtime.messages import MissionFacts

ROBOT_PATH = "#1c7ed6"
HUMAN_PATH = "#e8590c"
UNKNOWN_TYPE_COLOUR = (0.7, 0.7, 0.7, 1.0)
"""A body whose type is not in the default catalogue (a user's catalogue) is drawn grey."""
FLOOR_STAND_IN = ObjectType("floor", "floor", Tile(), 0.0, 0.0, (0.0, 0.0, 0.0),
                            (0.86, 0.84, 0.78, 1.0))


def map_figure(world: ConcreteWorld, mission: ConcreteMission | None, *, title: str,
               compact: bool = True, size: float = 6.5, margin: tuple[float, float] = (2.6, 0.8)
               ) -> tuple[Figure, Axes]:
    """A figure sized to the room (its longer side ``size`` inches, plus ``margin`` for the
    legend and title) with the room drawn from above."""
    from rei.generators.picture import draw_world  # noqa: PLC0415  (generators: lazily)

    min_x, min_y, max_x, max_y = world.bounds()
    scale = size / max(max_x - min_x, max_y - min_y, 1e-9)
    fig = new_figure(max(3.5, (max_x - min_x) * scale + margin[0]),
                     max(3.0, (max_y - min_y) * scale + margin[1]))
    ax = fig.add_subplot()
    draw_world(ax, world, mission, compact=compact, title=title)
    return fig, ax


def draw_human_paths(ax: Axes, paths: Paths) -> None:
    for name, path in paths.humans.items():
        ax.plot(path[:, 1], path[:, 2], color=HUMAN_PATH, linewidth=1.0, alpha=0.8,
                linestyle="--", label=f"human {name}" if len(paths.humans) < 4 else None)


def draw_signals(ax: Axes, robot: np.ndarray, events: list[SignalEvent]) -> None:
    """Where the robot was when each geometric signal fired (mission signals have no place)."""
    geometric = [e for e in events if not e.signal.startswith("SIG_MISSION_")]
    if not geometric:
        return
    xs = np.interp([e.time for e in geometric], robot[:, 0], robot[:, 1])
    ys = np.interp([e.time for e in geometric], robot[:, 0], robot[:, 2])
    bad = np.array([e.utility < 0 for e in geometric])
    ax.scatter(xs[bad], ys[bad], marker="x", color="#c92a2a", s=22, zorder=5,
               label="signal (negative utility)")
    ax.scatter(xs[~bad], ys[~bad], marker="o", facecolors="none", edgecolors="#2b8a3e",
               s=18, zorder=5, label="signal (positive utility)")


def draw_paths(ax: Axes, paths: Paths, events: list[SignalEvent]) -> None:
    """The campaign map's overlay: humans dashed, the robot's path in blue, signals."""
    draw_human_paths(ax, paths)
    robot = paths.robot
    ax.plot(robot[:, 1], robot[:, 2], color=ROBOT_PATH, linewidth=1.6, label="robot path")
    draw_signals(ax, robot, events)
    ax.legend(fontsize=TEXT_PT, loc="upper right")


def _object_type(body: BodySpec) -> ObjectType:
    """The body's catalogue type with the footprint that actually ran (from the manifest)."""
    known = default_catalogue().get(body.type)
    colour = known.colour if known is not None else UNKNOWN_TYPE_COLOUR
    return ObjectType(body.type, cast(Kind, body.role), body.footprint, body.height,
                      known.mass if known is not None else 0.0,
                      known.inertia if known is not None else (0.0, 0.0, 0.0), colour)


def world_from_manifest(manifest: WorldManifest) -> ConcreteWorld:
    """The concrete world a run's world.json describes (floors, walls, objects with their
    trajectories, the robot at its start pose), for drawing."""
    from rei.generators.concrete.model import (  # noqa: PLC0415
        ConcreteBlock,
        ConcreteObject,
        ConcreteWorld,
        Pose2D,
        Role,
        TimedPoint,
        TimedTrajectory,
    )

    tile = manifest.tile_size
    # world.json does not name the floors' type: every floor is drawn as the default tile
    floor_type = default_catalogue().get("floor_tile") or FLOOR_STAND_IN

    def cell(x: float, y: float) -> tuple[int, int]:
        return round(x / tile), round(y / tile)

    floors = tuple(ConcreteBlock(name, "floor", floor_type, cell(x, y), x, y, tile)
                   for name, x, y in manifest.floors)
    walls = tuple(ConcreteBlock(w.name, "wall", _object_type(w), cell(w.x, w.y), w.x, w.y, tile)
                  for w in manifest.walls)

    def concrete(body: BodySpec) -> ConcreteObject:
        trajectory = None
        if body.trajectory is not None:
            trajectory = TimedTrajectory(tuple(TimedPoint(t, x, y) for t, x, y in
                                               body.trajectory.points), body.trajectory.loop)
        return ConcreteObject(body.name, cast(Role, body.role), _object_type(body), "",
                              Pose2D(body.x, body.y, body.yaw), trajectory)

    return ConcreteWorld(manifest.world, str(manifest.folder), tile, floors, walls,
                         tuple(concrete(o) for o in manifest.objects), concrete(manifest.robot))



def mission_from_facts(name: str, world: ConcreteWorld, facts: MissionFacts) -> ConcreteMission:
    """The mission's goals as the picture code draws them, from the facts a trace's header
    carries (a run folder keeps no .mission file)."""
    from rei.generators.concrete.model import ConcreteGoal, ConcreteMission  # noqa: PLC0415

    goals = tuple(ConcreteGoal(g.name, world.floor_at(g.x, g.y) or "", g.x, g.y, g.heading,
                               g.tolerance, g.timeout) for g in facts.goals)
    return ConcreteMission(name, "", world, goals, facts.cycles, facts.time_limit,
                           facts.mission_max_speed)
