"""Seeded start-pose jitter: repeats explore, the same seed replays, the scene stays valid."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rei.catalogue import Box, Cylinder
from rei.runtime.artifacts.world import WorldManifest, load_manifest
from rei.runtime.errors import RunError
from rei.runtime.runs.session import run_into
from rei.runtime.simulation.assembly import generate_world
from rei.runtime.simulation.world.start_jitter import START_JITTER, StartJitter, jitter_start

from .records import EXAMPLES

NAVIGATION = EXAMPLES / "navigation" / "navigation.mission"


@pytest.fixture(scope="module")
def manifest(tmp_path_factory: pytest.TempPathFactory) -> WorldManifest:
    folder = tmp_path_factory.mktemp("world")
    generate_world(NAVIGATION, folder)
    return load_manifest(folder)


@settings(deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_jitter_stays_within_its_declared_ranges(manifest: WorldManifest, seed: int) -> None:
    start = jitter_start(manifest, seed)
    declared = (manifest.robot.x, manifest.robot.y, manifest.robot.yaw)
    assert start.declared == declared
    assert start.applied, start.reason  # the navigation example's start floor is open
    assert abs(start.pose[0] - declared[0]) <= START_JITTER.xy
    assert abs(start.pose[1] - declared[1]) <= START_JITTER.xy
    assert abs(math.degrees(start.pose[2] - declared[2])) <= START_JITTER.yaw_deg
    assert jitter_start(manifest, seed) == start  # a function of the seed only


def test_different_seeds_give_different_start_poses(manifest: WorldManifest) -> None:
    poses = {jitter_start(manifest, seed).pose for seed in range(20)}
    assert len(poses) == 20


def test_no_jitter_is_the_declared_pose(manifest: WorldManifest) -> None:
    start = jitter_start(manifest, 5, None)
    assert start.pose == start.declared and not start.applied


def test_a_pose_that_would_touch_an_obstacle_falls_back_to_the_declared_one(
        manifest: WorldManifest) -> None:
    robot = manifest.robot
    hx, _ = robot.footprint.half_extents()
    # A crate 1 mm beside the robot's front: any jitter towards it overlaps, none away from it.
    crate = replace(manifest.objects[0], name="tight", x=robot.x + hx + 0.001 + 0.1,
                    y=robot.y, yaw=0.0, footprint=Box(0.2, 0.2))
    tight = replace(manifest, objects=(crate,), walls=())
    outcomes = [jitter_start(tight, seed) for seed in range(40)]
    fallbacks = [s for s in outcomes if not s.applied]
    assert fallbacks and all(s.pose == s.declared and "'tight'" in s.reason for s in fallbacks)
    assert any(s.applied for s in outcomes)


def _reach_x(shape: Box | Cylinder, yaw: float) -> float:
    """How far a footprint turned by ``yaw`` reaches along +x from its centre."""
    if isinstance(shape, Cylinder):
        return shape.radius
    hx, hy = shape.half_extents()
    return hx * abs(math.cos(yaw)) + hy * abs(math.sin(yaw))


def _outline(box: Box, x: float, y: float, yaw: float, n: int = 400
             ) -> list[tuple[float, float]]:
    hx, hy = box.half_extents()
    local = [(hx * (2 * i / n - 1), side * hy) for i in range(n + 1) for side in (-1, 1)]
    local += [(side * hx, hy * (2 * i / n - 1)) for i in range(n + 1) for side in (-1, 1)]
    c, s = math.cos(yaw), math.sin(yaw)
    return [(x + c * u - s * v, y + s * u + c * v) for u, v in local]


@pytest.mark.parametrize("robot_shape", [Box(0.281, 0.306), Cylinder(0.15)])
@pytest.mark.parametrize("obstacle", [Box(0.4, 0.6), Cylinder(0.25)])
def test_touching_is_allowed_and_overlapping_is_not(
        manifest: WorldManifest, robot_shape: Box | Cylinder, obstacle: Box | Cylinder) -> None:
    robot = replace(manifest.robot, x=0.0, y=0.0, yaw=0.0, footprint=robot_shape)
    gap = robot_shape.half_extents()[0] + obstacle.half_extents()[0]
    # The post exactly touches the robot's +x side at the declared pose.
    post = replace(manifest.objects[0], name="post", x=gap, y=0.0, yaw=0.0, footprint=obstacle)
    scene = replace(manifest, robot=robot, objects=(post,), walls=(),
                    floors=(("start", 0.0, 0.0),))
    assert jitter_start(scene, 0, StartJitter(0.0, 0.0)).applied  # touching is allowed
    starts = [jitter_start(scene, seed) for seed in range(80)]
    for start in starts:
        # What an exact oracle says about the drawn pose (the declared one on fallback is
        # only reached from a drawn pose that overlaps).
        x, y, yaw = start.pose
        if isinstance(robot_shape, Cylinder) and isinstance(obstacle, Cylinder):
            overlaps = math.hypot(gap - x, y) < gap - 1e-9
        elif isinstance(obstacle, Cylinder):  # a turned box's outline, densely sampled
            clearance = min(math.hypot(gap - px, py) for px, py in _outline(robot_shape, x, y,
                                                                            yaw))
            if abs(clearance - obstacle.radius) < 1e-3:
                continue  # too close to call for a sampled oracle
            overlaps = clearance < obstacle.radius
        else:  # flat faces meet; the y jitter stays within them
            overlaps = x + _reach_x(robot_shape, yaw) > robot_shape.half_extents()[0] + 1e-9
        if start.applied:
            assert not overlaps, start
        else:
            assert start.pose == start.declared and "'post'" in start.reason
    assert any(s.applied for s in starts) and any(not s.applied for s in starts)


def test_a_bad_range_is_a_located_error() -> None:
    with pytest.raises(RunError, match="'xy'.*non-negative"):
        StartJitter(xy=-0.1)


def _run(out: Path, seed: int, variation: bool = True) -> dict[str, object]:
    run_into(NAVIGATION, out, seed=seed, duration=1.0, variation=variation)
    data: dict[str, object] = json.loads((out / "summary.json").read_text())
    return data


@pytest.mark.slow
def test_a_run_starts_where_its_summary_says_and_the_same_seed_gives_the_same_bytes(
        tmp_path: Path) -> None:
    first = _run(tmp_path / "a", 11)
    _run(tmp_path / "b", 11)
    for name in ("summary.json", "trace.jsonl", "events.csv"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
    measurements = first["measurements"]
    assert isinstance(measurements, dict)
    jitter = measurements["variations"]["start_jitter"]
    assert jitter["applied"] and (jitter["dx"], jitter["dy"]) != (0.0, 0.0)
    # The first sample's true pose is the jittered pose: body, odometry and summary agree.
    trace = (tmp_path / "a" / "trace.jsonl").read_text().splitlines()
    sample = json.loads(trace[1])
    assert sample["robot_pose"][:2] == pytest.approx([jitter["x"], jitter["y"]], abs=1e-9)
    assert sample["belief"]["odom"][:2] == pytest.approx(sample["robot_pose"][:2])
    other = _run(tmp_path / "c", 12)["measurements"]
    assert isinstance(other, dict)
    assert other["variations"]["start_jitter"]["x"] != jitter["x"]
    off = _run(tmp_path / "off", 11, variation=False)["measurements"]
    assert isinstance(off, dict)
    assert off["variations"]["start_jitter"] == {
        "applied": False, "reason": "variation off", "dx": 0.0, "dy": 0.0, "dyaw_deg": 0.0,
        "x": 0.0, "y": 0.0, "yaw": 0.0}
