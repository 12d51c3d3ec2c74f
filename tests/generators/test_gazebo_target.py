"""The `gazebo` target: SDF 1.9 that Debian's `ign sdf -k` accepts, with catalogue geometry."""

from __future__ import annotations

import subprocess
from dataclasses import replace
from pathlib import Path

import pytest
from lxml import etree

from rei.catalogue import Tile
from rei.generators.errors import GenerationError
from rei.generators.targets import GenerationRequest, check_target
from rei.generators.targets.gazebo import TARGET
from tests.conftest import example_files, require_tool
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
    assert models["bot"].findtext("pose") == "0 0 0 0 0 -1.570796"


def test_every_block_and_object_is_a_model(request_for: RequestFor) -> None:
    request = request_for(example_files(".room")[0])
    world = request.world
    root = etree.fromstring(sdf_of(request))
    names = [m.get("name") for m in root.iter("model")]
    expected = (["ground_plane"] + [b.name for b in world.floors + world.walls]
                + [o.name for o in world.objects] + [world.robot.name])
    assert names == expected
    wall = next(m for m in root.iter("model") if m.get("name") == world.walls[0].name)
    assert wall.findtext("static") == "true"
    assert wall.findtext("link/collision/geometry/box/size") == "1 1 1.2"
    assert root.get("version") == "1.9"


def test_robot_option_none_leaves_the_robot_to_the_launch_file(request_for: RequestFor) -> None:
    path = example_files(".room")[0]
    request = request_for(path, robot="none")
    names = [m.get("name") for m in etree.fromstring(sdf_of(request)).iter("model")]
    assert request.world.robot.name not in names
    with pytest.raises(GenerationError, match="option robot: expected one of"):
        sdf_of(request_for(path, robot="tb3"))


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


@pytest.mark.slow
def test_the_launch_targets_robot_less_world_passes_ign_sdf_check(
    request_for: RequestFor, tmp_path: Path,
) -> None:
    from rei.generators.targets.launch import TARGET as LAUNCH

    files = LAUNCH.generate(request_for(example_files(".mission")[0])).files
    ign_check(tmp_path, files["world.sdf"])
