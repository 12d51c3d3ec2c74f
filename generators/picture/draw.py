"""Drawing a concrete world from above into a matplotlib Axes: floors, walls, objects, humans
with their trajectories, the robot with its heading, and a mission's numbered goals.

Coordinates are the concrete model's (metres, +x right, +y up), so the picture shows exactly
what the generators place. This module must never choose a backend, open a window or write
files: it only adds artists to the Axes it is given.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, FancyArrow, Patch, Rectangle
from matplotlib.patches import Polygon as PolygonPatch

from rei.catalogue import Box, Cylinder, ObjectType, Polygon
from rei.generators.concrete import ConcreteMission, ConcreteObject, ConcreteWorld
from rei.lang.room.spline import CatmullRom, walked_path

WALL_EDGE = "#3a3a40"
FLOOR_EDGE = "#b8b4a8"
TRAJECTORY = "#d9480f"
TRAJECTORY_TEXT = "#8f3507"
"""The trajectory's orange, dark enough for 4.5:1 contrast on white."""
ROBOT = "#1c7ed6"
GOAL = "#2b8a3e"
CURVE_STEP = 0.05
"""Metres between the drawn points of a walked curve."""


def _rotated(points: Sequence[tuple[float, float]], x: float, y: float, yaw: float
             ) -> list[tuple[float, float]]:
    c, s = math.cos(yaw), math.sin(yaw)
    return [(x + c * px - s * py, y + s * px + c * py) for px, py in points]


def footprint_patch(otype: ObjectType, x: float, y: float, yaw: float, **style: object) -> Patch:
    """The catalogue footprint of a type at a pose, as a patch (tiles as the unit square)."""
    fp = otype.footprint
    if isinstance(fp, Cylinder):
        return Circle((x, y), fp.radius, **style)
    if isinstance(fp, Box):
        hx, hy = fp.half_extents()
        corners = [(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)]
    elif isinstance(fp, Polygon):
        corners = list(fp.points)
    else:
        corners = [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)]
    return PolygonPatch(_rotated(corners, x, y, yaw), closed=True, **style)


def _label(ax: Axes, text: str, x: float, y: float, size: float, **style: object) -> None:
    ax.text(x, y, text, ha="center", va="center", fontsize=size, zorder=9,
            bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.7},
            **style)  # type: ignore[arg-type]


def _draw_trajectory(ax: Axes, obj: ConcreteObject, compact: bool) -> None:
    """The curve the body walks (the animator's Catmull-Rom spline, not the straight lines
    between its vertices), its vertices, and an arrow head per segment."""
    assert obj.trajectory is not None
    points = obj.trajectory.points
    spline = CatmullRom(np.array([p.t for p in points]), np.array([(p.x, p.y) for p in points]),
                        obj.trajectory.loop)
    _, path = walked_path(spline, CURVE_STEP)
    ax.plot(path[:, 0], path[:, 1], color=TRAJECTORY, linewidth=1.2, linestyle="--", zorder=5)
    ax.plot([p.x for p in points], [p.y for p in points], linestyle="none", marker="o",
            markersize=3, color=TRAJECTORY, zorder=5)
    # One arrow head per segment, half way through its time, shows the walking direction.
    for a, b in zip(points, points[1:], strict=False):
        mid = (a.t + b.t) / 2
        (mx, my), (nx, ny) = spline.position(mid), spline.position(mid + 1e-3 * (b.t - a.t))
        if math.hypot(nx - mx, ny - my) < 1e-12:
            continue
        ax.annotate("", xy=(nx, ny), xytext=(mx, my), zorder=5,
                    arrowprops={"arrowstyle": "-|>", "color": TRAJECTORY, "lw": 1.2})
    if not compact:
        last = len(obj.trajectory.points) - (1 if obj.trajectory.loop else 0)
        for point in obj.trajectory.points[:last]:
            # Below-right of the vertex, outside a human's footprint standing on it.
            # Dark text on an opaque white box: readable on any floor colour (issue 27).
            ax.annotate(f"{point.t:.4g}s", (point.x, point.y), xytext=(7, -15),
                        textcoords="offset points", fontsize=9, color=TRAJECTORY_TEXT,
                        zorder=9, bbox={"boxstyle": "round,pad=0.15", "fc": "white",
                                        "ec": TRAJECTORY, "lw": 0.6, "alpha": 0.92})


def draw_world(ax: Axes, world: ConcreteWorld, mission: ConcreteMission | None = None, *,
               compact: bool = False, title: str | None = None) -> None:
    """Draw ``world`` (and the goals of ``mission``) into ``ax``; ``compact`` drops labels."""
    tile = world.tile_size
    half = tile / 2
    for block in world.floors:
        ax.add_patch(Rectangle((block.x - half, block.y - half), tile, tile,
                               facecolor=block.type.colour, edgecolor=FLOOR_EDGE, linewidth=0.4,
                               zorder=1))
    for block in world.walls:
        ax.add_patch(Rectangle((block.x - half, block.y - half), tile, tile,
                               facecolor=block.type.colour, edgecolor=WALL_EDGE, linewidth=0.6,
                               hatch=None if compact else "///", zorder=2))
    label_size = 9.0
    for obj in world.objects:
        style = {"facecolor": obj.type.colour, "edgecolor": "black", "linewidth": 0.6,
                 "zorder": 6 if obj.role == "human" else 4}
        ax.add_patch(footprint_patch(obj.type, obj.pose.x, obj.pose.y, obj.pose.yaw, **style))
        if obj.trajectory is not None:
            _draw_trajectory(ax, obj, compact)
        if not compact:
            _label(ax, obj.name, obj.pose.x, obj.pose.y - 0.38 * tile, label_size)
    robot = world.robot
    ax.add_patch(footprint_patch(robot.type, robot.pose.x, robot.pose.y, robot.pose.yaw,
                                 facecolor=ROBOT, edgecolor="black", linewidth=0.8, zorder=7))
    length = 0.4 * tile
    ax.add_patch(FancyArrow(robot.pose.x, robot.pose.y, length * math.cos(robot.pose.yaw),
                            length * math.sin(robot.pose.yaw), width=0.03 * tile,
                            head_width=0.14 * tile, head_length=0.12 * tile,
                            length_includes_head=True, color="white", zorder=8))
    if not compact:
        _label(ax, robot.name, robot.pose.x, robot.pose.y - 0.38 * tile, label_size, color=ROBOT)
    if mission is not None:
        _draw_goals(ax, mission, compact)
    min_x, min_y, max_x, max_y = world.bounds()
    ax.set_xlim(min_x - 0.2 * tile, max_x + 0.2 * tile)
    ax.set_ylim(min_y - 0.2 * tile, max_y + 0.2 * tile)
    ax.set_aspect("equal")
    ax.set_title(title if title is not None else _title(world, mission),
                 fontsize=8 if compact else 11)
    if compact:
        ax.set_xticks([])
        ax.set_yticks([])
    else:
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.tick_params(labelsize=9)
        _legend(ax, world, mission)


def _title(world: ConcreteWorld, mission: ConcreteMission | None) -> str:
    if mission is None:
        return f"room {world.name}"
    return f"mission {mission.name} in room {world.name}"


def _draw_goals(ax: Axes, mission: ConcreteMission, compact: bool) -> None:
    # Goals on the same floor (a round trip's start and end) share one marker and label.
    numbers: dict[tuple[float, float], list[str]] = {}
    for index, goal in enumerate(mission.goals, start=1):
        numbers.setdefault((goal.x, goal.y), []).append(str(index))
        ax.add_patch(Circle((goal.x, goal.y), goal.tolerance, facecolor=GOAL, alpha=0.18,
                            edgecolor=GOAL, linewidth=1.0, zorder=3))
        if goal.yaw is not None:
            tip = (goal.x + 0.45 * math.cos(goal.yaw), goal.y + 0.45 * math.sin(goal.yaw))
            ax.annotate("", xy=tip, xytext=(goal.x, goal.y), zorder=8,
                        arrowprops={"arrowstyle": "-|>", "color": GOAL, "lw": 1.5})
    if len(mission.goals) > 1:
        xs = [g.x for g in mission.goals]
        ys = [g.y for g in mission.goals]
        ax.plot(xs, ys, color=GOAL, linewidth=0.8, linestyle=":", zorder=3)
    for (x, y), labels in numbers.items():
        ax.text(x + 0.28, y + 0.28, ",".join(labels), ha="center", va="center",
                fontsize=7 if compact else 9, fontweight="bold", color="white", zorder=10,
                bbox={"boxstyle": "circle,pad=0.25", "fc": GOAL, "ec": "white", "lw": 0.8})


def _legend(ax: Axes, world: ConcreteWorld, mission: ConcreteMission | None) -> None:
    floor_colour = world.floors[0].type.colour if world.floors else "white"
    handles: list[object] = [
        Patch(facecolor=floor_colour, edgecolor=FLOOR_EDGE, label="floor"),
        Patch(facecolor=world.walls[0].type.colour if world.walls else "grey",
              edgecolor=WALL_EDGE, hatch="///", label="wall"),
        Patch(facecolor=ROBOT, edgecolor="black", label=f"robot ({world.robot.type.name})"),
    ]
    if world.objects:
        handles.append(Patch(facecolor="#c9a77c", edgecolor="black", label="object"))
    if world.animated:
        handles.append(Line2D([], [], color=TRAJECTORY, linestyle="--", marker="o", markersize=3,
                              label="trajectory (time at vertex)"))
    if mission is not None:
        handles.append(Line2D([], [], color=GOAL, marker="o", linestyle=":", markersize=7,
                              label=f"goals in order (x{mission.cycles} cycles)"
                              if mission.cycles > 1 else "goals in order"))
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=9,
              frameon=False)
