"""The `launch` target: how to run a test — a ROS 2 launch file and REI's own run configuration.

Written files (thesis 6.2.1, "robot component launch"):

``rei_test.launch.xml``
    ROS 2 launch XML: Gazebo (``ros_gz_sim``) with ``world.sdf``, the TurtleBot3 Waffle spawned
    at the robot's start pose, the ``ros_gz_bridge``, Nav2 with SLAM, and REI's animator, data
    collector and (for a .mission) mission executor with their configuration files.
``world.sdf``
    The `gazebo` target's world without the robot placeholder (the launch file spawns the robot).
``animator.json``
    The trajectories of the animated objects (control vertices with times, world frame).
``run.json``
    REI's run configuration: sources, artifacts, monitor specification, seed, controller, duration.

ROS 2 rather than ROS 1: SDF 1.9 worlds are read by Gazebo Sim, which ROS 2 drives through
``ros_gz``; ROS 1's Gazebo Classic reads older SDF, and ROS 1 reached its end of life in 2025.
Options: ``seed`` (whole number, default 0), ``monitor`` (a .vepl path relative to the input
file, default ``default``: REI's bundled specification), ``controller`` (default
``navigator``), ``duration`` (seconds; default the mission's time limit, 60 for a room).
This module must never write files itself or read the textX model.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import jinja2

from rei.generators.concrete import ConcreteMission, ConcreteWorld
from rei.generators.errors import GenerationError
from rei.generators.output import OutputTree
from rei.generators.targets import GenerationRequest
from rei.generators.targets.gazebo import GazeboTarget
from rei.generators.templating import (
    check_xml,
    dump_json,
    make_environment,
    normalise_angle,
    relative_to,
    render,
    template_loader,
)

LAUNCH = "rei_test.launch.xml"
WORLD = "world.sdf"
ANIMATOR = "animator.json"
RUN = "run.json"
MISSION_XML = "../mission/mission.xml"
"""Where `rei-gen generate --target all` puts the mission target's file, seen from here."""
RUN_FORMAT = "rei-run/1"
DEFAULT_ROOM_DURATION = 60.0


@dataclass(frozen=True)
class RunOptions:
    seed: int
    monitor: str
    controller: str
    duration: float


def run_options(options: Mapping[str, str], mission: ConcreteMission | None) -> RunOptions:
    """The launch target's options, checked; GenerationError names the option and the value."""
    seed_text = options.get("seed", "0")
    if not seed_text.isdigit():
        raise GenerationError(f"option seed: expected a whole number >= 0, found '{seed_text}'")
    default_duration = mission.time_limit if mission is not None else DEFAULT_ROOM_DURATION
    duration_text = options.get("duration")
    duration = default_duration
    if duration_text is not None:
        try:
            duration = float(duration_text)
        except ValueError:
            duration = math.nan
        if not math.isfinite(duration) or duration <= 0:
            raise GenerationError(f"option duration: expected a finite number of seconds > 0, "
                                  f"found '{duration_text}'")
    controller = options.get("controller", "navigator")
    if not controller:
        raise GenerationError("option controller: expected a controller name, found ''")
    return RunOptions(int(seed_text), options.get("monitor", "default"), controller, duration)


def animator_config(world: ConcreteWorld) -> dict[str, Any]:
    return {
        "format": "rei-animator/1",
        "world": world.name,
        "objects": [
            {"name": o.name, "role": o.role, "type": o.type.name, "loop": o.trajectory.loop,
             "points": [{"t": p.t, "x": p.x, "y": p.y} for p in o.trajectory.points]}
            for o in world.animated if o.trajectory is not None
        ],
    }


def run_config(request: GenerationRequest, opts: RunOptions) -> dict[str, Any]:
    world, mission = request.world, request.mission
    assert world is not None
    robot = world.robot
    return {
        "format": RUN_FORMAT,
        "name": mission.name if mission is not None else world.name,
        "sources": {
            "comment": "paths relative to the folder of the generated file's input",
            "room": relative_to(world.source, str(request.source)),
            "mission": request.source.name if mission is not None else None,
            "monitor": opts.monitor,
        },
        "artifacts": {
            "comment": "paths relative to this file",
            "launch": LAUNCH,
            "gazebo_world": WORLD,
            "animator": ANIMATOR,
            "mission_xml": MISSION_XML if mission is not None else None,
        },
        "seed": opts.seed,
        "controller": opts.controller,
        "duration": opts.duration,
        "robot": {"name": robot.name, "type": robot.type.name, "floor": robot.floor,
                  "x": robot.pose.x, "y": robot.pose.y, "yaw": normalise_angle(robot.pose.yaw)},
    }


@dataclass(frozen=True)
class LaunchTarget:
    name: str = "launch"
    description: str = "a ROS 2 launch file for the robot's components and REI's run.json"
    accepts: tuple[str, ...] = (".room", ".mission")
    options: tuple[str, ...] = ("controller", "duration", "monitor", "seed")
    """The --option keys this target reads."""
    loader: jinja2.BaseLoader | None = field(default=None, compare=False)

    def generate(self, request: GenerationRequest) -> OutputTree:
        world, mission = request.world, request.mission
        if world is None:
            raise GenerationError(f"target 'launch' expected a .room or .mission file, found "
                                  f"'{request.source.name}'")
        opts = run_options(request.options, mission)
        robot = world.robot
        env = make_environment(self.loader or template_loader("launch"), xml=True)
        launch = render(env, "rei_test.launch.xml.j2", robot=robot, mission=mission,
                        source_file=request.source.name, mission_xml=MISSION_XML,
                        robot_yaw=normalise_angle(robot.pose.yaw),
                        spawn_z=world.floor(robot.floor).type.height)
        check_xml(launch, LAUNCH)
        tree = OutputTree()
        tree.add_text(LAUNCH, launch)
        tree.add_text(WORLD, GazeboTarget().render_world(request, "none"))
        tree.add_text(ANIMATOR, dump_json(animator_config(world)))
        tree.add_text(RUN, dump_json(run_config(request, opts)))
        return tree


TARGET = LaunchTarget()
