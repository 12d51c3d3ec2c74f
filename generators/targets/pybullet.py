"""The `pybullet` target: the world as files pybullet loads directly (thesis 4.1.3, 6.2.1).

One URDF per body *type* (``urdf/<type>.urdf``; walls get ``urdf/wall_<type>.urdf`` of the
room's tile size) and a manifest, ``world.json``, that places every instance: name, role,
type, URDF, pose, footprint, height, and the timed trajectory and behaviour (scripted,
yielding, social) of animated bodies. A URDF per
type rather than one world file because pybullet loads a URDF at any pose with
``useFixedBase`` per instance, the same file serves every instance of a type, and the
manifest keeps what pybullet cannot hold (roles, footprints, trajectories, laser and drive
specs) beside it for the runtime. Floors are listed in the manifest but not loaded as bodies:
the runtime simulates the plane without gravity, so floor tiles would only cost contacts.
Polygon footprints are approximated by their bounding box. This module must never write
files itself (``write_tree`` does) or import pybullet.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import jinja2

from rei.catalogue import ObjectType, codec
from rei.generators.concrete import ConcreteObject, ConcreteWorld
from rei.generators.errors import GenerationError
from rei.generators.output import OutputTree
from rei.generators.targets import GenerationRequest
from rei.generators.templating import (
    check_xml,
    dump_json,
    make_environment,
    normalise_angle,
    relative_to,
    render,
    template_loader,
)

MANIFEST = "world.json"
MANIFEST_VERSION = 3
"""3: animated bodies carry a ``behaviour``."""


def footprint_json(otype: ObjectType, tile: float) -> dict[str, Any]:
    """The footprint as the manifest stores it: the shape the simulator builds (a box or a
    cylinder; rei.catalogue.codec)."""
    return codec.footprint_json(codec.simulated(otype.footprint, tile))


def _urdf(env: jinja2.Environment, otype: ObjectType, tile: float, fixed: bool) -> str:
    fp = footprint_json(otype, tile)
    mass = 0.0 if fixed else otype.mass
    inertia = (0.0, 0.0, 0.0) if fixed else otype.inertia
    context: dict[str, Any] = {"type_name": otype.name, "kind": otype.kind, "colour": otype.colour,
                               "mass": mass, "inertia": inertia, "height": otype.height,
                               "shape": fp["shape"], "radius": fp.get("radius", 0.0),
                               "size_x": fp.get("size", [0.0, 0.0])[0],
                               "size_y": fp.get("size", [0.0, 0.0])[1]}
    text = render(env, "body.urdf.j2", **context)
    check_xml(text, f"URDF of '{otype.name}'")
    return text


def _body(obj: ConcreteObject, urdf: str, fixed: bool, tile: float) -> dict[str, Any]:
    body: dict[str, Any] = {
        "name": obj.name, "role": obj.role, "type": obj.type.name, "urdf": urdf,
        "fixed": fixed, "floor": obj.floor,
        "pose": [obj.pose.x, obj.pose.y, normalise_angle(obj.pose.yaw)],
        "z": obj.type.height / 2, "height": obj.type.height, "mass": obj.type.mass,
        "footprint": footprint_json(obj.type, tile), "trajectory": None,
    }
    if obj.trajectory is not None:
        body["trajectory"] = {"loop": obj.trajectory.loop,
                              "points": [[p.t, p.x, p.y] for p in obj.trajectory.points]}
        start = obj.trajectory.start_when
        if start is not None:
            body["trajectory"]["start_when"] = {"floor": start.floor, "x": start.x,
                                                "y": start.y, "within": start.within}
        body["behaviour"] = obj.behaviour
    return body


def build_manifest(world: ConcreteWorld, source_name: str, room_file: str) -> tuple[
        dict[str, Any], dict[str, tuple[ObjectType, bool]]]:
    """The manifest and the URDF files it names (path -> (type, fixed base))."""
    tile = world.tile_size
    urdfs: dict[str, tuple[ObjectType, bool]] = {}
    walls = []
    for block in world.walls:
        path = f"urdf/wall_{block.type.name}.urdf"
        urdfs[path] = (block.type, True)
        walls.append({"name": block.name, "role": "wall", "type": block.type.name, "urdf": path,
                      "fixed": True, "floor": None, "pose": [block.x, block.y, 0.0],
                      "z": block.type.height / 2, "height": block.type.height, "mass": 0.0,
                      "footprint": {"shape": "box", "size": [tile, tile]}, "trajectory": None})
    objects = []
    for obj in world.objects:
        # Static objects never move: a fixed base makes them immovable and cheap to simulate.
        fixed = obj.role == "static"
        path = f"urdf/{obj.type.name}{'_fixed' if fixed else ''}.urdf"
        urdfs[path] = (obj.type, fixed)
        objects.append(_body(obj, path, fixed, tile))
    robot_type = world.robot.type
    if robot_type.drive is None or robot_type.laser is None:
        raise GenerationError(f"robot type '{robot_type.name}' expected a drive and a laser in "
                              f"the catalogue, found "
                              f"{'no drive' if robot_type.drive is None else 'no laser'}")
    robot_path = f"urdf/{robot_type.name}.urdf"
    urdfs[robot_path] = (robot_type, False)
    robot = _body(world.robot, robot_path, False, tile)
    drive, laser = robot_type.drive, robot_type.laser
    robot["drive"] = {"max_linear": drive.max_linear, "max_angular": drive.max_angular,
                      "wheel_separation": drive.wheel_separation,
                      "wheel_radius": drive.wheel_radius,
                      "max_linear_accel": drive.max_linear_accel,
                      "max_linear_decel": drive.max_linear_decel,
                      "max_angular_accel": drive.max_angular_accel,
                      "max_angular_decel": drive.max_angular_decel}
    robot["laser"] = {"beams": laser.beams, "min_range": laser.min_range,
                      "max_range": laser.max_range, "rate": laser.rate, "fov": laser.fov,
                      "mount": [laser.mount_x, laser.mount_y, laser.mount_z],
                      "noise": laser.noise}
    manifest = {
        "version": MANIFEST_VERSION, "generator": "rei-gen pybullet", "world": world.name,
        "source": {"input": source_name, "room": room_file},
        "tile_size": tile, "bounds": list(world.bounds()),
        "floors": [[f.name, f.x, f.y] for f in world.floors],
        "walls": walls, "objects": objects, "robot": robot,
    }
    return manifest, urdfs


@dataclass(frozen=True)
class PybulletTarget:
    name: str = "pybullet"
    description: str = ("the world as URDF files per body type and a world.json manifest "
                        "for pybullet")
    accepts: tuple[str, ...] = (".room", ".mission")
    options: tuple[str, ...] = ()
    loader: jinja2.BaseLoader | None = field(default=None, compare=False)

    def generate(self, request: GenerationRequest) -> OutputTree:
        world = request.world
        if world is None:
            raise GenerationError(f"target 'pybullet' expected a .room or .mission file, found "
                                  f"'{request.source.name}'")
        manifest, urdfs = build_manifest(world, request.source.name,
                                         relative_to(world.source, str(request.source)))
        env = make_environment(self.loader or template_loader("pybullet"), xml=True)
        tree = OutputTree()
        for path, (otype, fixed) in sorted(urdfs.items()):
            tree.add_text(path, _urdf(env, otype, world.tile_size, fixed))
        tree.add_text(MANIFEST, dump_json(manifest))
        return tree


TARGET = PybulletTarget()
