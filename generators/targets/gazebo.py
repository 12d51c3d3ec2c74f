"""The `gazebo` target: an SDF 1.9 world for Gazebo Sim (thesis 4.1.3.2, Figure 13; 6.2.1-6.2.2).

Every floor tile and wall block becomes a static model with a box collision and visual;
every object gets its catalogue geometry (box, cylinder, or a polygon extruded as an SDF
polyline), its mass and inertia. The robot is built from its catalogue entry: a base of its
footprint, height, mass and inertia on two driven wheels (the drive's wheel radius and
separation) and two frictionless casters, Gazebo's differential-drive system on
``cmd_vel`` (odometry on ``odom``), and, when the type has a laser, a ``gpu_lidar`` with the
catalogue's beams, field of view, range, rate, mount and noise on ``scan``. Humans with a
trajectory are ``<actor>``s walking a scripted trajectory whose waypoints are sampled from the
same Catmull-Rom spline REI's animator walks (rei.lang.room.spline), facing their
direction of motion; humans without one stand as models. An actor's script cannot start on
the robot's position without a Gazebo plugin, so a trajectory with a start trigger (``start
when robot within D of FLOOR``) starts at its *planned* time instead: when a robot driving
straight from its start at its drive's top speed would first be within D of the floor (the
earliest it could be), with a comment in the SDF saying so. Dynamic objects stand at their start
pose (Gazebo has no scripted motion for a plain model). Option ``robot=none`` leaves the robot
out. The text is checked to be well-formed XML here; tests check it with ``ign sdf -k``. This
module must never write files itself or read the textX model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import jinja2
import numpy as np

from rei.catalogue import Box, Cylinder, ObjectType, Polygon
from rei.catalogue.model import solid_inertia
from rei.generators.concrete import ConcreteObject, ConcreteWorld
from rei.generators.concrete.model import TimedTrajectory
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
from rei.lang.room.spline import CatmullRom

OUTPUT = "world.sdf"
ROBOT_MODES = ("model", "none")
STEP = 0.001
"""Seconds per physics step: Gazebo's default, the one TurtleBot3's worlds use."""
WAYPOINT_STEP = 0.25
"""Seconds between an actor's waypoints; Gazebo interpolates linearly between them."""
ACTOR_SKIN = "https://fuel.gazebosim.org/1.0/Mingfei/models/actor/tip/files/meshes/walk.dae"
"""The walking person of Gazebo's own actor examples (origin at the hips, 1 m up)."""
ACTOR_HIP_HEIGHT = 1.0
WHEEL_MASS = 0.05
"""kg per wheel and caster: the catalogue gives the robot's mass, all of it in the base."""
WHEEL_WIDTH = 0.018
SYSTEMS = (
    ("ignition-gazebo-physics-system", "ignition::gazebo::systems::Physics"),
    ("ignition-gazebo-user-commands-system", "ignition::gazebo::systems::UserCommands"),
    ("ignition-gazebo-scene-broadcaster-system", "ignition::gazebo::systems::SceneBroadcaster"),
    ("ignition-gazebo-sensors-system", "ignition::gazebo::systems::Sensors"),
)
"""World systems of Gazebo Fortress (the `ign` 12 tools): a world naming any system gets no
defaults, and the laser needs the sensors system."""


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


@dataclass(frozen=True)
class Wheel:
    """A wheel or caster link of the robot, relative to the robot's model frame."""

    name: str
    pose: tuple[float, ...]
    radius: float
    mass: float
    inertia: tuple[float, float, float]
    sphere: bool


@dataclass(frozen=True)
class Lidar:
    pose: tuple[float, ...]
    beams: int
    min_angle: float
    max_angle: float
    min_range: float
    max_range: float
    rate: float
    noise: float


@dataclass(frozen=True)
class RobotModel:
    """The robot under test, from its catalogue entry: a base on a differential drive."""

    name: str
    type_name: str
    pose: tuple[float, ...]
    base: SdfModel
    """The base link's geometry, mass and inertia (its pose is the model's own)."""
    base_z: float
    """Height of the base's bottom above the floor (the wheels' clearance)."""
    wheels: tuple[Wheel, ...]
    wheel_separation: float
    wheel_radius: float
    max_linear: float
    max_angular: float
    lidar: Lidar | None


@dataclass(frozen=True)
class Waypoint:
    time: float
    pose: tuple[float, ...]


@dataclass(frozen=True)
class Actor:
    """A human walking its trajectory as a Gazebo actor script."""

    name: str
    loop: bool
    delay: float
    waypoints: tuple[Waypoint, ...]
    behaviour: str
    trigger_note: str = ""
    """Why the delay is a planned start time (a trajectory with a start trigger), or empty."""


def _object_model(obj: ConcreteObject, comment: str, z: float = 0.0) -> SdfModel:
    otype: ObjectType = obj.type
    fp = otype.footprint
    # Everything but the geometry; each branch below fills in its shape.
    common = SdfModel(name=obj.name, static=obj.role == "static",
                      pose=(obj.pose.x, obj.pose.y, z, 0.0, 0.0, normalise_angle(obj.pose.yaw)),
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


def robot_model(world: ConcreteWorld) -> RobotModel:
    """The robot of ``world`` built from its catalogue type; GenerationError when the type has
    no drive (a robot Gazebo could not move)."""
    robot = world.robot
    otype = robot.type
    drive = otype.drive
    if drive is None:
        raise GenerationError(f"robot '{robot.name}': catalogue type '{otype.name}' has no "
                              f"drive: expected [types.{otype.name}.drive] with the wheel "
                              f"radius and separation, found none")
    r = drive.wheel_radius
    # The base rests on its wheels: its bottom clears the floor by half a wheel radius and it
    # keeps the catalogue's overall height.
    clearance = r / 2
    base = _object_model(robot, "")
    height = max(otype.height - clearance, clearance)
    base = replace(base, pose=(0.0, 0.0, 0.0, 0.0, 0.0, 0.0), height=height,
                   size=base.size[:2] + (height,) if base.size else ())
    if base.mass > 0 and base.inertia == (0.0, 0.0, 0.0):
        base = replace(base, inertia=solid_inertia(otype.footprint, base.height, base.mass))
    half_x = max(otype.footprint.half_extents()[0], r)
    wheel_i = solid_inertia(Cylinder(r), WHEEL_WIDTH, WHEEL_MASS)
    caster_r = clearance  # touches the floor, like the wheels: the base stands level
    caster_i = (2 * WHEEL_MASS * caster_r ** 2 / 5,) * 3
    wheels = (
        Wheel("left_wheel", (0.0, drive.wheel_separation / 2, r, -math.pi / 2, 0.0, 0.0), r,
              WHEEL_MASS, wheel_i, False),
        Wheel("right_wheel", (0.0, -drive.wheel_separation / 2, r, -math.pi / 2, 0.0, 0.0), r,
              WHEEL_MASS, wheel_i, False),
        Wheel("front_caster", (half_x - caster_r, 0.0, caster_r, 0.0, 0.0, 0.0), caster_r,
              WHEEL_MASS, caster_i, True),
        Wheel("rear_caster", (-half_x + caster_r, 0.0, caster_r, 0.0, 0.0, 0.0), caster_r,
              WHEEL_MASS, caster_i, True),
    )
    laser = otype.laser
    lidar = None if laser is None else Lidar(
        # The catalogue mounts the laser above the floor; the sensor sits on the raised base.
        pose=(laser.mount_x, laser.mount_y, laser.mount_z - clearance, 0.0, 0.0, 0.0),
        beams=laser.beams,
        min_angle=-laser.fov / 2, max_angle=laser.fov / 2 - (
            laser.fov / laser.beams if math.isclose(laser.fov, 2 * math.pi) else 0.0),
        min_range=laser.min_range, max_range=laser.max_range, rate=laser.rate,
        noise=laser.noise)
    floor_z = world.floor(robot.floor).type.height
    return RobotModel(robot.name, otype.name,
                      (robot.pose.x, robot.pose.y, floor_z, 0.0, 0.0,
                       normalise_angle(robot.pose.yaw)),
                      base, clearance, wheels, drive.wheel_separation, r, drive.max_linear,
                      drive.max_angular, lidar)


def planned_start(trajectory: TimedTrajectory, robot: ConcreteObject) -> tuple[float, str]:
    """When a triggered trajectory starts in Gazebo (seconds), and the SDF comment saying
    why: the earliest a robot driving straight from its start at its drive's top speed meets
    the trigger. (0, "") for a trajectory without a trigger."""
    start = trajectory.start_when
    if start is None:
        return 0.0, ""
    drive = robot.type.drive
    speed = drive.max_linear if drive is not None and drive.max_linear > 0 else 1.0
    way = max(0.0, math.hypot(start.x - robot.pose.x, start.y - robot.pose.y) - start.within)
    planned = way / speed
    return planned, (f"In REI this trajectory starts when the robot comes within "
                     f"{start.within:g} m of floor '{start.floor}'; an actor script cannot "
                     f"wait for the robot without a plugin, so here it starts at the planned "
                     f"time {planned:.3f} s (the robot driving straight there at "
                     f"{speed:g} m/s).")


def actor_of(obj: ConcreteObject, floor_z: float, robot: ConcreteObject | None = None) -> Actor:
    """The human's trajectory sampled from the animator's spline every WAYPOINT_STEP seconds
    (and at every control vertex), facing its direction of motion; ``robot`` times a start
    trigger (planned_start)."""
    trajectory = obj.trajectory
    assert trajectory is not None
    planned, note = planned_start(trajectory, robot) if robot is not None else (0.0, "")
    times = np.array([p.t for p in trajectory.points], dtype=float)
    spline = CatmullRom(times, np.array([[p.x, p.y] for p in trajectory.points], dtype=float),
                        trajectory.loop)
    t0, end = float(times[0]), float(times[-1])
    count = max(int(math.floor((end - t0) / WAYPOINT_STEP + 1e-9)), 1)
    samples = sorted({round(t0 + k * WAYPOINT_STEP, 9) for k in range(count + 1)}
                     | {round(float(t), 9) for t in times})
    samples = [t for t in samples if t <= end]
    yaw = normalise_angle(obj.pose.yaw)
    waypoints = []
    for t in samples:
        # The velocity just after t (just before the end): the heading the walker shows there.
        probe = min(t + 1e-3, end - 1e-3) if end - t0 > 2e-3 else t
        vx, vy = spline.velocity(probe)
        if math.hypot(vx, vy) > 1e-6:
            yaw = math.atan2(vy, vx)
        x, y = spline.position(t)
        waypoints.append(Waypoint(t - t0, (x, y, floor_z + ACTOR_HIP_HEIGHT, 0.0, 0.0, yaw)))
    return Actor(obj.name, trajectory.loop, t0 + planned, tuple(waypoints), obj.behaviour, note)


def world_models(world: ConcreteWorld) -> list[SdfModel]:
    """The static blocks and every object without an actor, in declaration order."""
    models = [SdfModel(name=b.name, static=True, pose=(b.x, b.y, 0.0, 0.0, 0.0, 0.0), shape="box",
                       height=b.type.height, colour=b.type.colour,
                       size=(b.size, b.size, b.type.height))
              for b in world.floors + world.walls]
    for obj in world.objects:
        if obj.role == "human" and obj.trajectory is not None:
            continue
        comment = ""
        if obj.role == "dynamic":
            comment = (f"dynamic object '{obj.name}': stands at its start pose here (REI's "
                       f"runtime moves it in pybullet)" if obj.trajectory is not None else
                       f"dynamic object '{obj.name}' without a trajectory: stands still")
        elif obj.role == "human":
            comment = f"human '{obj.name}' without a trajectory: stands still"
        models.append(_object_model(obj, comment))
    return models


def world_actors(world: ConcreteWorld) -> list[Actor]:
    return [actor_of(o, world.floor(o.floor).type.height, world.robot) for o in world.objects
            if o.role == "human" and o.trajectory is not None]


@dataclass(frozen=True)
class GazeboTarget:
    name: str = "gazebo"
    description: str = ("an SDF 1.9 world for Gazebo Sim (floors, walls, objects, walking humans, "
                        "the robot with its drive and laser)")
    accepts: tuple[str, ...] = (".room", ".mission")
    options: tuple[str, ...] = ("robot",)
    """The --option keys this target reads."""
    loader: jinja2.BaseLoader | None = field(default=None, compare=False)

    def generate(self, request: GenerationRequest) -> OutputTree:
        if request.world is None:
            raise GenerationError(f"target 'gazebo' expected a .room or .mission file, found "
                                  f"'{request.source.name}'")
        tree = OutputTree()
        tree.add_text(OUTPUT, self.render_world(request, request.options.get("robot", "model")))
        return tree

    def render_world(self, request: GenerationRequest, robot: str = "model") -> str:
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
        env = make_environment(self.loader or template_loader("gazebo"), xml=True)
        text = render(env, "world.sdf.j2", world=world, models=world_models(world),
                      actors=world_actors(world), skin=ACTOR_SKIN, systems=SYSTEMS,
                      wheel_width=WHEEL_WIDTH,
                      robot=robot_model(world) if robot == "model" else None,
                      ground=ground, step=STEP, source_file=request.source.name)
        check_xml(text, OUTPUT)
        return text


TARGET = GazeboTarget()
