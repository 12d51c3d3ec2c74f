"""The `launch` target: how to run a test — REI's ``run.json`` and a ROS 2 launch file.

Written files (thesis 6.2.1, "robot component launch"):

``run.json`` (a .mission only)
    REI's run configuration (format ``rei-run/1``): ``rei run --config run.json [-o DIR]``
    runs, monitors and judges the mission exactly like the equivalent command line. Its
    paths are relative to itself and point into ``sources/``.
``sources/``  (a .mission only)
    Copies of the mission, its room, the room's own catalogue file and the ``.vepl`` of
    option ``monitor``, in their relative layout, so the folder runs wherever it is moved.
``world.sdf``
    The `gazebo` target's world: the robot built from its catalogue entry (drive, laser)
    and the humans walking their trajectories as actors.
``rei_test.launch.xml``
    ROS 2 launch XML for your navigation stack in Gazebo Sim: the world (``ros_gz_sim``),
    the ``ros_gz_bridge`` topics the robot's software reads and writes (clock, scan, odom,
    cmd_vel, tf), Gazebo's poses of the moving models as ground truth on
    ``/rei/ground_truth``, the laser's static transform (``tf2_ros``), the launch file of
    your navigation stack, given as the ``navigation_launch`` argument, and
    ``ros2 bag record`` (MCAP storage) of exactly the topics `rei replay BAG --mission`
    reads (argument ``bag``: the folder; ``record:=false`` turns it off). It names no
    program that ROS 2 and Gazebo do not ship; REI's own judged run is
    `rei run --config run.json`.
``rei_bag_map.toml``
    The ``rei replay --map`` file for those bags (ground truth topic, Gazebo's world frame).

ROS 2 rather than ROS 1: SDF 1.9 worlds are read by Gazebo Sim, which ROS 2 drives through
``ros_gz``; ROS 1's Gazebo Classic reads older SDF, and ROS 1 reached its end of life in 2025.
Options (a .mission only): ``seed`` (whole number, default 0), ``monitor`` (a .vepl path
relative to the input file, default ``default``: REI's bundled specification),
``controller`` (default ``reference``), ``duration`` (seconds; default the mission's time
limit); `--param NAME=VALUE` sets run.json's ``parameters`` (checked against that
.vepl). This module must never write files itself or read the textX model.
"""

from __future__ import annotations

import math
import os.path
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import jinja2

from rei.generators.concrete import ConcreteWorld
from rei.generators.errors import GenerationError
from rei.generators.output import OutputTree
from rei.generators.targets import GenerationRequest
from rei.generators.targets.gazebo import GazeboTarget, robot_model
from rei.generators.templating import (
    check_xml,
    dump_json,
    make_environment,
    render,
    template_loader,
)
from rei.lang.suggest import did_you_mean

LAUNCH = "rei_test.launch.xml"
WORLD = "world.sdf"
RUN = "run.json"
SOURCES = "sources"
RUN_FORMAT = "rei-run/1"
RUN_OPTIONS = ("controller", "duration", "monitor", "seed")
BUILT_IN_CONTROLLERS = ("reference", "teleop", "teleop:circle", "teleop:forward_backward")
"""`rei run`'s built-in controllers (rei.runtime.robot.BUILT_IN; a test keeps them equal)."""


@dataclass(frozen=True)
class RunOptions:
    seed: int
    monitor: str | None
    """The .vepl path relative to the input file; None: REI's default specification."""
    controller: str
    duration: float | None
    """None: the mission's time limit."""


def run_options(options: Mapping[str, str]) -> RunOptions:
    """The launch target's options, checked; GenerationError names the option and the value."""
    seed_text = options.get("seed", "0")
    if not seed_text.isdigit():
        raise GenerationError(f"option seed: expected a whole number >= 0, found '{seed_text}'")
    duration_text = options.get("duration")
    duration = None
    if duration_text is not None:
        try:
            duration = float(duration_text)
        except ValueError:
            duration = math.nan
        if not math.isfinite(duration) or duration <= 0:
            raise GenerationError(f"option duration: expected a finite number of seconds > 0, "
                                  f"found '{duration_text}'")
    controller = options.get("controller", "reference")
    if controller not in BUILT_IN_CONTROLLERS and ":" not in controller:
        raise GenerationError(f"option controller: expected one of "
                              f"{', '.join(BUILT_IN_CONTROLLERS)} or module:Class, found "
                              f"'{controller}'" + did_you_mean(controller,
                                                               list(BUILT_IN_CONTROLLERS)))
    monitor = options.get("monitor", "default")
    return RunOptions(int(seed_text), None if monitor == "default" else monitor, controller,
                      duration)


def source_files(request: GenerationRequest, opts: RunOptions) -> list[Path]:
    """Every file the run reads: the mission, its room, the room's catalogue, the .vepl."""
    from rei.lang.workspace import load_room  # noqa: PLC0415  (the room's catalogue path)

    world = request.world
    assert world is not None
    files = [request.source, Path(world.source)]
    catalogue = load_room(world.source).room
    if catalogue is not None and catalogue.catalogue_path is not None:
        files.append(Path(catalogue.catalogue_path))
    if opts.monitor is not None:
        vepl = request.source.parent / opts.monitor
        if vepl.suffix != ".vepl" or not vepl.is_file():
            raise GenerationError(f"option monitor: expected a .vepl file (relative to "
                                  f"'{request.source.name}') or 'default', found "
                                  f"'{opts.monitor}'")
        files.append(vepl)
    return files


def copy_sources(files: list[Path]) -> dict[str, bytes]:
    """The files under ``sources/``, keeping their layout below their common folder (so the
    mission still finds its room and the room its catalogue)."""
    absolute = [os.path.abspath(f) for f in files]
    common = os.path.commonpath([os.path.dirname(a) for a in absolute])
    copies: dict[str, bytes] = {}
    for path, original in zip(absolute, files, strict=True):
        rel = os.path.relpath(path, common).replace(os.sep, "/")
        try:
            copies[f"{SOURCES}/{rel}"] = Path(path).read_bytes()
        except OSError as exc:
            raise GenerationError(f"cannot read '{original}': {exc.strerror}") from None
    return copies


def check_parameters(vepl: Path | None, parameters: tuple[tuple[str, float], ...]) -> None:
    """`--param` values against the run's .vepl (None: REI's default one): each name
    declared, every parameter rule kept, as `rei run` will check them (LanguageError)."""
    from rei.lang.vepl.document import load_vepl  # noqa: PLC0415  (textX: only when asked)

    load_vepl(vepl, parameters)


def run_config(sources: list[str], has_vepl: bool, opts: RunOptions,
               parameters: tuple[tuple[str, float], ...] = ()) -> dict[str, Any]:
    """run.json: the same run as `rei run MISSION -o DIR [--param ...]` with these options
    (``parameters`` only when some are set, so a file without them reads as before)."""
    extra = {"parameters": dict(parameters)} if parameters else {}
    return {
        "format": RUN_FORMAT,
        "mission": sources[0],
        "vepl": sources[-1] if has_vepl else None,
        "controller": opts.controller,
        "seed": opts.seed,
        "duration": opts.duration,
        "physics_rate": 100.0,
        "odom_drift": 0.0,
        "laser_noise": None,
        "variation": True,
        "monitor": True,
        **extra,
    }


def bridge_topics() -> str:
    """ros_gz_bridge arguments: ROS topic@ROS type[ (from Gazebo) or ] (to Gazebo) Gazebo type."""
    return " ".join((
        "/clock@rosgraph_msgs/msg/Clock[gz.msgs.Clock",
        "/scan@sensor_msgs/msg/LaserScan[gz.msgs.LaserScan",
        "/odom@nav_msgs/msg/Odometry[gz.msgs.Odometry",
        "/tf@tf2_msgs/msg/TFMessage[gz.msgs.Pose_V",
        "/cmd_vel@geometry_msgs/msg/Twist]gz.msgs.Twist",
    ))


GROUND_TRUTH = "/rei/ground_truth"
"""The ROS topic the launch file bridges Gazebo's poses of every moving model onto
(tf2_msgs/msg/TFMessage): the ground truth REI judges by, kept off /tf so the stack's own
tree (map -> odom -> base_link) is untouched."""
RECORDED_TOPICS = ("/clock", "/tf", "/tf_static", "/odom", "/scan", "/cmd_vel", GROUND_TRUTH,
                   "/navigate_to_pose/_action/status")
"""Exactly what `rei replay BAG --mission` reads (rei.runtime.observation.recordings.foreign; a
test keeps
the two equal): the time, the stack's frames, its belief, its commands, the ground truth
and Nav2's navigate_to_pose status (a hidden action topic: recorded with
--include-hidden-topics)."""
BAG_MAP = "rei_bag_map.toml"


def ground_truth_bridge(world: str) -> str:
    """ros_gz_bridge argument: Gazebo's poses of the world's dynamic models (gz.msgs.Pose_V)
    as TFMessage (the world's frame -> each model's name)."""
    return f"/world/{world}/dynamic_pose/info@tf2_msgs/msg/TFMessage[gz.msgs.Pose_V"


def bag_map(world: str) -> str:
    """`rei replay --map` for the bags this launch file records: ground truth from
    GROUND_TRUTH, its parent frame Gazebo's world."""
    return (f"# Generated by rei-gen (target \"launch\"): how `rei replay BAG --mission M "
            f"--map {BAG_MAP}`\n"
            f"# reads the bags rei_test.launch.xml records (docs/recording.md).\n"
            f"[topics]\n\"/tf\" = \"{GROUND_TRUTH}\"\n\n[frames]\nmap = \"{world}\"\n")


@dataclass(frozen=True)
class LaunchTarget:
    name: str = "launch"
    description: str = ("REI's run.json (rei run --config) and a ROS 2 launch file for your "
                        "navigation stack in Gazebo Sim")
    accepts: tuple[str, ...] = (".room", ".mission")
    options: tuple[str, ...] = RUN_OPTIONS
    """The --option keys this target reads."""
    runs_missions: bool = True
    """`--param` with a .mission goes into run.json's ``parameters`` (the run's .vepl)."""
    loader: jinja2.BaseLoader | None = field(default=None, compare=False)

    def generate(self, request: GenerationRequest) -> OutputTree:
        world, mission = request.world, request.mission
        if world is None:
            raise GenerationError(f"target 'launch' expected a .room or .mission file, found "
                                  f"'{request.source.name}'")
        tree = OutputTree()
        if mission is not None:
            opts = run_options(request.options)
            files = source_files(request, opts)
            if request.parameters:
                check_parameters(files[-1] if opts.monitor is not None else None,
                                 request.parameters)
            copies = copy_sources(files)
            for rel, data in copies.items():
                tree.add_bytes(rel, data)
            tree.add_text(RUN, dump_json(run_config(list(copies), opts.monitor is not None,
                                                    opts, request.parameters)))
        else:
            given = sorted(set(request.options) & set(RUN_OPTIONS))
            if given:
                raise GenerationError(f"option {given[0]}: expected a .mission file (a room "
                                      f"alone has nothing to run), found "
                                      f"'{request.source.name}'")
        tree.add_text(LAUNCH, self.render_launch(request, world))
        tree.add_text(BAG_MAP, bag_map(world.name))
        tree.add_text(WORLD, GazeboTarget().render_world(request))
        return tree

    def render_launch(self, request: GenerationRequest, world: ConcreteWorld) -> str:
        robot = robot_model(world)
        env = make_environment(self.loader or template_loader("launch"), xml=True)
        launch = render(env, "rei_test.launch.xml.j2", robot=robot, mission=request.mission,
                        source_file=request.source.name, bridge=bridge_topics(),
                        ground_truth=ground_truth_bridge(world.name),
                        ground_truth_source=f"/world/{world.name}/dynamic_pose/info",
                        ground_truth_topic=GROUND_TRUTH, record=" ".join(RECORDED_TOPICS),
                        bag_map=BAG_MAP)
        check_xml(launch, LAUNCH)
        return launch


TARGET = LaunchTarget()
