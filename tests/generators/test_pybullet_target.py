"""The `pybullet` target: URDFs per body type plus a manifest, loaded by pybullet in DIRECT mode."""

from __future__ import annotations

import json
from pathlib import Path

import pybullet as p
import pytest
from lxml import etree

from rei.generators.concrete.build import load_concrete_mission
from rei.generators.output import write_tree
from rei.generators.targets import GenerationRequest, check_target, get_target
from rei.runtime.artifacts.world import load_manifest
from rei.runtime.simulation.world.bullet import BulletWorld
from tests.conftest import EXAMPLES, example_files

MISSIONS = example_files(".mission")


def _generate(mission_file: Path, out: Path) -> None:
    mission = load_concrete_mission(mission_file)
    tree = get_target("pybullet").generate(GenerationRequest(mission_file, mission.world, mission))
    write_tree(tree, out)


def test_the_target_conforms() -> None:
    assert check_target(get_target("pybullet")) == []


@pytest.mark.parametrize("mission_file", MISSIONS, ids=lambda f: f.stem)
def test_world_loads_in_direct_mode_with_every_body_in_place(mission_file: Path,
                                                             tmp_path: Path) -> None:
    _generate(mission_file, tmp_path)
    mission = load_concrete_mission(mission_file)
    world = mission.world
    manifest = load_manifest(tmp_path)
    with BulletWorld(manifest, 100.0) as sim:
        bodies = p.getNumBodies(physicsClientId=sim.client)
        assert bodies == len(world.walls) + len(world.objects) + 1
        for bid, wall in zip(sim.wall_ids, world.walls, strict=False):
            assert sim.pose(bid)[:2] == pytest.approx((wall.x, wall.y), abs=1e-6)
        for bid, obj in zip(sim.object_ids, world.objects, strict=False):
            x, y, _ = sim.pose(bid)
            assert (x, y) == pytest.approx((obj.pose.x, obj.pose.y), abs=1e-6)
            z = p.getBasePositionAndOrientation(bid, physicsClientId=sim.client)[0][2]
            assert z == pytest.approx(obj.type.height / 2, abs=1e-6)
        assert sim.pose(sim.robot_id) == pytest.approx(
            (world.robot.pose.x, world.robot.pose.y, world.robot.pose.yaw), abs=1e-6)


def test_one_urdf_per_body_type_and_valid_xml(tmp_path: Path) -> None:
    mission_file = EXAMPLES / "small_dense" / "small_dense.mission"
    _generate(mission_file, tmp_path)
    urdfs = sorted(f.name for f in (tmp_path / "urdf").iterdir())
    assert urdfs == ["box_fixed.urdf", "chair_fixed.urdf", "pillar_fixed.urdf",
                     "shelf_fixed.urdf", "table_fixed.urdf", "turtlebot3_waffle.urdf",
                     "wall_wall.urdf"]
    for name in urdfs:
        root = etree.parse(str(tmp_path / "urdf" / name)).getroot()
        assert root.tag == "robot" and root.find("link/collision/geometry") is not None
    manifest = json.loads((tmp_path / "world.json").read_text())
    assert manifest["robot"]["laser"]["beams"] == 360
    assert {o["role"] for o in manifest["objects"]} == {"static"}


def test_generation_is_deterministic() -> None:
    mission_file = EXAMPLES / "medium_sparse" / "medium_sparse.mission"
    mission = load_concrete_mission(mission_file)
    request = GenerationRequest(mission_file, mission.world, mission)
    first = get_target("pybullet").generate(request).files
    second = get_target("pybullet").generate(request).files
    assert first == second
    manifest = json.loads(first["world.json"])
    human = [o for o in manifest["objects"] if o["role"] == "human"][0]
    # A loop's trajectory ends where it starts; a total-only time is spread by arc length.
    points = human["trajectory"]["points"]
    assert points[0][1:] == points[-1][1:] and points[-1][0] == pytest.approx(80.0)
