"""The `gazebo` target: an SDF 1.9 world for Gazebo users (thesis 4.1.3.2, Figure 13).

Every floor tile and wall block becomes a static model with a box collision and visual;
every object gets its catalogue geometry (box, cylinder, or a polygon extruded as an SDF
polyline), its mass and inertia; humans and dynamic objects are non-static models that REI's
animator moves; the robot is a placeholder box of the TurtleBot3's footprint (the real model
is spawned by the generated ROS launch file; option ``robot=none`` leaves it out). The text is
checked to be well-formed XML here; tests check it with ``ign sdf -k``. This module must never
write files itself or read the textX model.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import jinja2

from rei.catalogue import Box, Cylinder, ObjectType, Polygon
from rei.generators.concrete import ConcreteObject, ConcreteWorld
from rei.generators.errors import GenerationError
from rei.generators.output import OutputTree
from rei.generators.targets import GenerationRequest
from rei.generators.templating import (
    check_xml,
    make_environment,
    normalise_angle,
    render,
    template_loader,
)

OUTPUT = "world.sdf"
ROBOT_MODES = ("placeholder", "none")
STEP = 0.001
"""Seconds per physics step: Gazebo's default, the one TurtleBot3's worlds use."""
ROBOT_URI = "https://fuel.gazebosim.org/1.0/OpenRobotics/models/TurtleBot3 Waffle"


@dataclass(frozen=True)
class SdfModel:
    """One <model> of the world, everything the template needs in plain numbers."""

    name: str
    static: bool
    pose: tuple[float, ...]
    shape: str
    height: float
    colour: tuple[float, ...]
    mass: float = 0.0
    inertia: tuple[float, float, float] = (0.0, 0.0, 0.0)
    size: tuple[float, ...] = ()
    radius: float = 0.0
    points: tuple[tuple[float, float], ...] = ()
    comment: str = ""

    @property
    def shape_pose(self) -> tuple[float, ...]:
        # Boxes and cylinders are centred on their pose; a polyline is extruded upwards from it.
        z = 0.0 if self.shape == "polyline" else self.height / 2
        return (0.0, 0.0, z, 0.0, 0.0, 0.0)


def _object_model(obj: ConcreteObject, comment: str) -> SdfModel:
    otype: ObjectType = obj.type
    fp = otype.footprint
    # Everything but the geometry; each branch below fills in its shape.
    common = SdfModel(name=obj.name, static=obj.role == "static",
                      pose=(obj.pose.x, obj.pose.y, 0.0, 0.0, 0.0, normalise_angle(obj.pose.yaw)),
                      shape="", height=otype.height, colour=otype.colour, mass=otype.mass,
                      inertia=otype.inertia, comment=comment)
    if isinstance(fp, Box):
        return replace(common, shape="box", size=(fp.size_x, fp.size_y, otype.height))
    if isinstance(fp, Cylinder):
        return replace(common, shape="cylinder", radius=fp.radius)
    if isinstance(fp, Polygon):
        return replace(common, shape="polyline", points=fp.points)
    raise GenerationError(f"object '{obj.name}' (on floor '{obj.floor}'): catalogue type "
                          f"'{otype.name}' has no geometry a simulator can use: expected a box, "
                          f"cylinder or polygon footprint, found {type(fp).__name__.lower()}")


def world_models(world: ConcreteWorld, robot: str = "placeholder") -> list[SdfModel]:
    models = [SdfModel(name=b.name, static=True, pose=(b.x, b.y, 0.0, 0.0, 0.0, 0.0), shape="box",
                       height=b.type.height, colour=b.type.colour,
                       size=(b.size, b.size, b.type.height))
              for b in world.floors + world.walls]
    for obj in world.objects:
        comment = {"static": "", "dynamic": f"dynamic object '{obj.name}': moved by REI's animator",
                   "human": f"human '{obj.name}': moved by REI's animator"}.get(obj.role, "")
        if obj.role in ("dynamic", "human") and obj.trajectory is None:
            comment = f"{obj.role} object '{obj.name}' without a trajectory: stands still"
        models.append(_object_model(obj, comment))
    if robot == "placeholder":
        models.append(_object_model(world.robot, (
            f"robot '{world.robot.name}' ({world.robot.type.name}): a placeholder of its "
            f"footprint; for the real model use <include><uri>{ROBOT_URI}</uri></include>")))
    return models


@dataclass(frozen=True)
class GazeboTarget:
    name: str = "gazebo"
    description: str = "an SDF 1.9 world for Gazebo (floors, walls, objects, humans, robot)"
    accepts: tuple[str, ...] = (".room", ".mission")
    options: tuple[str, ...] = ("robot",)
    """The --option keys this target reads."""
    loader: jinja2.BaseLoader | None = field(default=None, compare=False)

    def generate(self, request: GenerationRequest) -> OutputTree:
        if request.world is None:
            raise GenerationError(f"target 'gazebo' expected a .room or .mission file, found "
                                  f"'{request.source.name}'")
        tree = OutputTree()
        tree.add_text(OUTPUT, self.render_world(request, request.options.get("robot",
                                                                             "placeholder")))
        return tree

    def render_world(self, request: GenerationRequest, robot: str) -> str:
        if robot not in ROBOT_MODES:
            raise GenerationError(f"option robot: expected one of {', '.join(ROBOT_MODES)}, "
                                  f"found '{robot}'")
        world = request.world
        assert world is not None
        min_x, min_y, max_x, max_y = world.bounds()
        margin = 2 * world.tile_size
        # The plane is centred on the origin (the robot's floor), so it spans twice the farthest
        # block in each direction.
        ground = (max(abs(min_x), abs(max_x)) * 2 + margin,
                  max(abs(min_y), abs(max_y)) * 2 + margin)
        robot_comment = "" if robot == "placeholder" else (
            f"robot '{world.robot.name}' ({world.robot.type.name}) is spawned by the launch file "
            f"at x={world.robot.pose.x:g} y={world.robot.pose.y:g}")
        env = make_environment(self.loader or template_loader("gazebo"), xml=True)
        text = render(env, "world.sdf.j2", world=world, models=world_models(world, robot),
                      ground=ground, step=STEP, source_file=request.source.name,
                      robot_comment=robot_comment)
        check_xml(text, OUTPUT)
        return text


TARGET = GazeboTarget()
