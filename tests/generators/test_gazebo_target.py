"""The `gazebo` target: SDF 1.9 that Debian's `ign sdf -k` accepts, with catalogue geometry."""

from __future__ import annotations

import math
import subprocess
from dataclasses import replace
from pathlib import Path

import pytest
from lxml import etree

from rei.catalogue import Tile
from rei.generators.errors import GenerationError
from rei.generators.targets import GenerationRequest, check_target
from rei.generators.targets.gazebo import TARGET
from rei.runtime.artifacts.world import Trajectory
from rei.runtime.simulation.animator import spline_of
from tests.conftest import EXAMPLES, example_files, require_tool
from tests.generators.conftest import RequestFor, Write

POLYGON_ROOM = """room shapes {
    catalogue "types.toml"
    grid g {
        legend { "S" = floor s }
        "#######"
        "#S....#"
        "#.....#"
        "#.....#"
        "#######"
    }
    robot bot : turtlebot3_waffle on s heading 270
    object plate : wedge on g_1_3 heading 45
    object post : pillar on g_3_2
    dynamic trolley : cart on g_2_5 trajectory { g_2_5 at 0  g_2_1 at 9 }
    human idle on g_1_5
}"""
TYPES = """[types.wedge]
kind = "static"
footprint = { shape = "polygon", points = [[-0.3, -0.2], [0.3, -0.2], [0.0, 0.3]] }
height = 0.5
mass = 3.0
"""


def sdf_of(request: GenerationRequest) -> bytes:
    return TARGET.generate(request).files["world.sdf"]


def ign_check(tmp_path: Path, data: bytes, name: str = "world.sdf") -> None:
    ign = require_tool("ign")
    path = tmp_path / name
    path.write_bytes(data)
    result = subprocess.run([ign, "sdf", "-k", str(path)], capture_output=True, text=True,
                            check=False)
    assert result.returncode == 0 and "Valid." in result.stdout, result.stdout + result.stderr


def test_target_conforms() -> None:
    assert check_target(TARGET) == []


@pytest.mark.slow
@pytest.mark.parametrize("path", example_files(".room") + example_files(".mission"),
                         ids=lambda p: p.name)
def test_every_example_passes_ign_sdf_check(
    path: Path, request_for: RequestFor, tmp_path: Path,
) -> None:
    ign_check(tmp_path, sdf_of(request_for(path)))


@pytest.mark.slow
def test_polygons_humans_dynamic_objects_pass_ign_sdf_check(
    write: Write, request_for: RequestFor, tmp_path: Path,
) -> None:
    write("types.toml", TYPES)
    request = request_for(write("shapes.room", POLYGON_ROOM))
    data = sdf_of(request)
    ign_check(tmp_path, data)
    world = etree.fromstring(data).find("world")
    assert world is not None
    models = {m.get("name"): m for m in world.findall("model")}
    plate = models["plate"]
    assert [p.text for p in plate.findall("link/collision/geometry/polyline/point")] == [
        "-0.3 -0.2", "0.3 -0.2", "0 0.3"]
    assert plate.findtext("pose") == "2 0 0 0 0 0.785398"
    assert plate.findtext("static") == "true"
    assert models["trolley"].findtext("static") == "false"
    assert models["idle"].findtext("static") == "false"
    assert models["idle"].findtext("link/inertial/mass") == "75"
    assert models["post"].find("link/inertial") is None  # massless static pillar: no inertial
    assert models["bot"].findtext("pose") == "0 0 0.01 0 0 -1.570796"  # on its floor tile


def test_every_block_and_object_is_a_model_and_every_walking_human_an_actor(
    request_for: RequestFor,
) -> None:
    request = request_for(EXAMPLES / "navigation" / "navigation.room")
    world = request.world
    root = etree.fromstring(sdf_of(request))
    walking = [o.name for o in world.objects if o.role == "human" and o.trajectory is not None]
    assert walking == ["walker"]
    names = [m.get("name") for m in root.iter("model")]
    expected = (["ground_plane"] + [b.name for b in world.floors + world.walls]
                + [o.name for o in world.objects if o.name not in walking] + [world.robot.name])
    assert names == expected
    assert [a.get("name") for a in root.iter("actor")] == walking
    wall = next(m for m in root.iter("model") if m.get("name") == world.walls[0].name)
    assert wall.findtext("static") == "true"
    assert wall.findtext("link/collision/geometry/box/size") == "1 1 1.2"
    assert root.get("version") == "1.9"


def test_the_robot_is_built_from_its_catalogue_entry(request_for: RequestFor) -> None:
    request = request_for(EXAMPLES / "navigation" / "navigation.room")
    otype = request.world.robot.type
    drive, laser = otype.drive, otype.laser
    assert drive is not None and laser is not None
    root = etree.fromstring(sdf_of(request))
    robot = next(m for m in root.iter("model") if m.get("name") == request.world.robot.name)
    base = robot.find("link[@name='base_link']")
    assert base is not None
    assert float(base.findtext("inertial/mass")) == otype.mass
    sx, sy, _ = (float(v) for v in base.findtext("collision/geometry/box/size").split())
    assert (sx, sy) == (otype.footprint.size_x, otype.footprint.size_y)
    plugin = robot.find("plugin[@name='ignition::gazebo::systems::DiffDrive']")
    assert plugin is not None
    assert float(plugin.findtext("wheel_separation")) == drive.wheel_separation
    assert float(plugin.findtext("wheel_radius")) == drive.wheel_radius
    assert float(plugin.findtext("max_linear_velocity")) == drive.max_linear
    joints = {j.get("name"): j.get("type") for j in robot.findall("joint")}
    assert joints["left_wheel_joint"] == joints["right_wheel_joint"] == "revolute"
    left = robot.find("link[@name='left_wheel']")
    assert float(left.findtext("collision/geometry/cylinder/radius")) == drive.wheel_radius
    lidar = base.find("sensor[@type='gpu_lidar']/lidar")
    assert lidar is not None
    assert int(lidar.findtext("scan/horizontal/samples")) == laser.beams
    assert float(lidar.findtext("range/min")) == laser.min_range
    assert float(lidar.findtext("range/max")) == laser.max_range
    assert float(lidar.findtext("noise/stddev")) == laser.noise
    assert float(base.findtext("sensor/update_rate")) == laser.rate
    # A 360-degree laser: beams one increment apart all round, as REI's laser casts them.
    low, high = float(lidar.findtext("scan/horizontal/min_angle")), float(
        lidar.findtext("scan/horizontal/max_angle"))
    assert low == pytest.approx(-math.pi, abs=1e-6)
    assert high - low == pytest.approx(laser.fov * (1 - 1 / laser.beams), abs=1e-5)
    systems = {p.get("name") for p in root.find("world").findall("plugin")}
    assert "ignition::gazebo::systems::Sensors" in systems  # a lidar needs the sensors system


def test_actors_walk_the_animators_spline(request_for: RequestFor) -> None:
    """Waypoints lie on the Catmull-Rom spline the runtime walks, at every control vertex too,
    with times from the trajectory's start and the walker facing its motion."""
    request = request_for(EXAMPLES / "navigation" / "navigation.room")
    walker = next(o for o in request.world.objects if o.name == "walker")
    assert walker.trajectory is not None
    spline = spline_of(Trajectory(
        walker.trajectory.loop, tuple((p.t, p.x, p.y) for p in walker.trajectory.points)))
    root = etree.fromstring(sdf_of(request))
    actor = next(root.iter("actor"))
    assert actor.findtext("script/loop") == "true"
    waypoints = actor.findall("script/trajectory/waypoint")
    times = [float(w.findtext("time")) for w in waypoints]
    assert times == sorted(times) and times[0] == 0
    assert times[-1] == pytest.approx(walker.trajectory.duration)
    t0 = walker.trajectory.points[0].t
    for point in walker.trajectory.points:
        assert pytest.approx(point.t - t0, abs=1e-6) in times
    for w, t in zip(waypoints, times, strict=True):
        x, y, _z, _r, _p, yaw = (float(v) for v in w.findtext("pose").split())
        sx, sy = spline.position(t0 + t)
        assert (x, y) == (pytest.approx(sx, abs=1e-5), pytest.approx(sy, abs=1e-5))
        vx, vy = spline.velocity(min(t0 + t + 1e-3, t0 + times[-1] - 1e-3))
        if math.hypot(vx, vy) > 1e-3:
            assert math.cos(yaw - math.atan2(vy, vx)) == pytest.approx(1, abs=1e-4)


def test_robot_option_none_leaves_the_robot_out(request_for: RequestFor) -> None:
    path = example_files(".room")[0]
    request = request_for(path, robot="none")
    names = [m.get("name") for m in etree.fromstring(sdf_of(request)).iter("model")]
    assert request.world.robot.name not in names
    with pytest.raises(GenerationError, match="option robot: expected one of model, none"):
        sdf_of(request_for(path, robot="placeholder"))


def test_a_robot_type_without_a_drive_is_a_clear_error(request_for: RequestFor) -> None:
    request = request_for(example_files(".room")[0])
    world = request.world
    robot = replace(world.robot, type=replace(world.robot.type, drive=None))
    with pytest.raises(GenerationError, match=rf"robot '{robot.name}': catalogue type "
                                              rf"'{robot.type.name}' has no drive"):
        sdf_of(replace(request, world=replace(world, robot=robot)))


def test_a_catalogue_type_without_geometry_is_a_clear_error(request_for: RequestFor) -> None:
    request = request_for(example_files(".room")[0])
    world = request.world
    broken = replace(world.objects[0], type=replace(world.objects[0].type, footprint=Tile()))
    request = replace(request, world=replace(world, objects=(broken,) + world.objects[1:]))
    with pytest.raises(GenerationError, match=rf"object '{broken.name}'.*catalogue type "
                                              rf"'{broken.type.name}' has no geometry"):
        sdf_of(request)


def test_same_input_gives_the_same_bytes(request_for: RequestFor) -> None:
    path = example_files(".mission")[0]
    assert sdf_of(request_for(path)) == sdf_of(request_for(path))


