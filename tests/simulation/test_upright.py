"""Moving bodies stay upright in the planar world, and keep their mass (issue 25).

A person is driven by planar velocities, but a contact's impulse within a physics step turned
it about a horizontal axis and the tilt added up: a walker pressed against a table leaned
20-40 degrees, and the leaning cylinder touched a robot 0.3 m from its footprint (a 1,000-run
campaign's room_0337). The checks here drive a real pybullet person into a real table and into
the real robot, and are shown to fail on the physics without ``keep_upright``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import pybullet as p
import pytest

from rei.catalogue import Box
from rei.generators.concrete.build import load_concrete_mission
from rei.generators.output import write_tree
from rei.generators.targets import GenerationRequest, get_target
from rei.runtime.artifacts.world import BodySpec, WorldManifest, load_manifest
from rei.runtime.simulation.world import bullet
from tests.conftest import EXAMPLES

SPEED = 0.3
"""m/s: a person's walk, straight at the table's long side through its centre."""
STEPS = 300


@pytest.fixture(scope="module")
def manifest(tmp_path_factory: pytest.TempPathFactory) -> WorldManifest:
    mission_file = EXAMPLES / "navigation" / "navigation.mission"
    mission = load_concrete_mission(mission_file)
    out = tmp_path_factory.mktemp("world")
    write_tree(get_target("pybullet").generate(GenerationRequest(mission_file, mission.world,
                                                                 mission)), out)
    return load_manifest(out)


def _tilt(world: bullet.BulletWorld, bid: int) -> float:
    """Degrees between the body's axis and the vertical."""
    x, y, _, _ = p.getBasePositionAndOrientation(bid, physicsClientId=world.client)[1]
    return math.degrees(math.acos(min(1.0, 1.0 - 2.0 * (x * x + y * y))))


@dataclass(frozen=True)
class Walk:
    """What ``STEPS`` physics steps of a person walking into something left."""

    tilt: float
    """Degrees: the person's largest tilt from the vertical."""
    person_x: float
    robot_x: float
    mass: float


def _walk_into(manifest: WorldManifest, target: str) -> Walk:
    """Drive the person at ``SPEED`` towards -x into ``target``: the desk, or the robot
    standing 1 m beside it."""
    with bullet.BulletWorld(manifest, 100.0) as world:
        index = next(i for i, b in enumerate(manifest.objects) if b.role == "human")
        person = world.object_ids[index]
        desk = _desk(manifest)
        y = desk.y if target == "desk" else desk.y - 1.0
        if target == "robot":
            world.place(world.robot_id, (desk.x + 0.7, y, 0.0))
        world.place(person, (desk.x + 1.3, y, 0.0))
        tilt = 0.0
        for _ in range(STEPS):
            world.set_planar_velocity(person, -SPEED, 0.0, 0.0)
            world.drive_robot(0.0, 0.0, world.pose(world.robot_id)[2])
            world.step()
            tilt = max(tilt, _tilt(world, person))
        return Walk(tilt, world.pose(person)[0], world.pose(world.robot_id)[0],
                    p.getDynamicsInfo(person, -1, physicsClientId=world.client)[0])


def _desk(manifest: WorldManifest) -> BodySpec:
    return next(b for b in manifest.objects if b.name == "desk")


def _face(manifest: WorldManifest) -> float:
    """The x of a person's centre touching the desk's +x side."""
    desk = _desk(manifest)
    assert isinstance(desk.footprint, Box)
    return float(desk.x + desk.footprint.size_x / 2 + 0.25)


def test_a_person_walking_into_a_table_stays_upright_and_outside_it(
        manifest: WorldManifest) -> None:
    walk = _walk_into(manifest, "desk")
    assert walk.tilt < 0.5
    assert walk.mass == 75.0
    # Stopped at the table's face, not through it.
    assert walk.person_x == pytest.approx(_face(manifest), abs=0.01)


def test_a_person_walking_into_the_robot_stays_upright_and_shoves_it(
        manifest: WorldManifest) -> None:
    walk = _walk_into(manifest, "robot")
    assert walk.tilt < 0.5
    start = _desk(manifest).x + 0.7
    # The robot is shoved (a person walks into it), by less than the walk's own length.
    assert start - SPEED * STEPS / 100 < walk.robot_x < start - 0.05


def test_without_keep_upright_the_person_tips_against_the_table(
        manifest: WorldManifest, monkeypatch: pytest.MonkeyPatch) -> None:
    """The tilt check can fail: the old physics tipped the person (5-40 degrees)."""
    monkeypatch.setattr(bullet, "keep_upright", lambda *_: None)
    assert _walk_into(manifest, "desk").tilt > 2.0


def test_an_upright_person_of_garbage_mass_walks_through_the_table(
        manifest: WorldManifest, monkeypatch: pytest.MonkeyPatch) -> None:
    """The face and mass checks can fail. pybullet's changeDynamics given the inertia alone
    (no ``mass``) read the mass from uninitialised memory: 1e189 kg in one run, 1e241 in
    another, and such a person walked through the desk. That garbage is not reproducible on
    demand, so it is set here."""
    def garbage_mass(bid: int, client: int) -> None:
        izz = p.getDynamicsInfo(bid, -1, physicsClientId=client)[2][2]
        p.changeDynamics(bid, -1, mass=1e189, localInertiaDiagonal=(1e9, 1e9, izz),
                         physicsClientId=client)

    monkeypatch.setattr(bullet, "keep_upright", garbage_mass)
    walk = _walk_into(manifest, "desk")
    assert walk.mass != 75.0
    assert walk.person_x < _face(manifest) - 0.2
