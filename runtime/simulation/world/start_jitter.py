"""Seeded start-pose jitter of the robot: repeats of a mission explore, not replay.

Repeats of a campaign differ by their seed; without variation the seed only changes the laser
noise, so ten repeats of a deterministic navigator are ten times the same run. A small,
declared jitter of the robot's start pose (within its start floor, never into an obstacle)
makes each repeat a slightly different but equally valid instance of the same scene.

The draw comes from its own generator, ``np.random.default_rng([seed, 2])``, so the run's main
stream (laser and odometry noise, ``np.random.default_rng(seed)``) draws exactly what it drew
before; the same seed gives the same jitter. This module must never import pybullet: the
overlap test is plain 2D geometry on the manifest's footprints.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from rei.catalogue import Box, Cylinder, Footprint
from rei.runtime.artifacts.world import BodySpec, WorldManifest
from rei.runtime.errors import RunError

JITTER_STREAM = 2
"""Second word of the jitter generator's seed: ``default_rng([seed, JITTER_STREAM])``. Other
per-run variations use other words, so each has its own stream and adding one never changes
what another draws."""


@dataclass(frozen=True)
class StartJitter:
    """Uniform ranges of the start-pose offset: x and y in metres, yaw in degrees (±)."""

    xy: float = 0.05
    yaw_deg: float = 5.0

    def __post_init__(self) -> None:
        for name, value in (("xy", self.xy), ("yaw_deg", self.yaw_deg)):
            if not (math.isfinite(value) and value >= 0):
                raise RunError(f"start jitter: expected '{name}' to be a non-negative finite "
                               f"number, found {value}")


START_JITTER = StartJitter()
"""REI's default: ±5 cm in x and y, ±5° of yaw — below a tile's size and a laser beam's spread,
so the scene stays the declared one while the navigator's trajectory does not replay."""


@dataclass(frozen=True)
class JitteredStart:
    """The start pose a run used, and how it was obtained (recorded in the run summary)."""

    declared: tuple[float, float, float]
    pose: tuple[float, float, float]
    applied: bool
    """False when the drawn pose left the start floor or overlapped a body (the declared pose
    is used instead) or when jitter is off."""
    reason: str

    def to_json(self) -> dict[str, Any]:
        dx, dy = self.pose[0] - self.declared[0], self.pose[1] - self.declared[1]
        return {"applied": self.applied, "reason": self.reason,
                "dx": dx, "dy": dy, "dyaw_deg": math.degrees(self.pose[2] - self.declared[2]),
                "x": self.pose[0], "y": self.pose[1], "yaw": self.pose[2]}


def jitter_start(manifest: WorldManifest, seed: int,
                 jitter: StartJitter | None = START_JITTER) -> JitteredStart:
    """The robot's start pose for a run with ``seed`` (the declared one if ``jitter`` is None)."""
    robot = manifest.robot
    declared = (robot.x, robot.y, robot.yaw)
    if jitter is None:
        return JitteredStart(declared, declared, False, "variation off")
    rng = np.random.default_rng([seed & 0xFFFFFFFFFFFFFFFF, JITTER_STREAM])
    # Always three draws in this order, whatever is rejected later: the stream stays aligned.
    dx, dy = (float(v) for v in rng.uniform(-jitter.xy, jitter.xy, size=2))
    dyaw = math.radians(float(rng.uniform(-jitter.yaw_deg, jitter.yaw_deg)))
    pose = (robot.x + dx, robot.y + dy, robot.yaw + dyaw)
    if not _on_start_floor(manifest, pose):
        return JitteredStart(declared, declared, False, "drawn pose leaves the start floor")
    blocker = next((b.name for b in manifest.walls + manifest.objects
                    if _overlap(robot.footprint, pose, b)), None)
    if blocker is not None:
        return JitteredStart(declared, declared, False, f"drawn pose overlaps '{blocker}'")
    return JitteredStart(declared, pose, True, "")


def with_robot_pose(manifest: WorldManifest, pose: tuple[float, float, float]) -> WorldManifest:
    """The manifest with the robot standing at ``pose``: the one source every consumer reads
    (the pybullet body, odometry and the controller's context then agree)."""
    return replace(manifest, robot=replace(manifest.robot, x=pose[0], y=pose[1], yaw=pose[2]))


def _on_start_floor(manifest: WorldManifest, pose: tuple[float, float, float]) -> bool:
    """The centre stays on the floor tile the robot was declared on."""
    robot = manifest.robot
    if not manifest.floors:
        return True
    _, fx, fy = min(manifest.floors,
                    key=lambda f: (f[1] - robot.x) ** 2 + (f[2] - robot.y) ** 2)
    half = manifest.tile_size / 2
    return abs(pose[0] - fx) <= half and abs(pose[1] - fy) <= half


def _corners(fp: Box, x: float, y: float, yaw: float) -> np.ndarray:
    hx, hy = fp.half_extents()
    local = np.array([(hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy)])
    c, s = math.cos(yaw), math.sin(yaw)
    return np.asarray(local @ np.array([[c, s], [-s, c]]) + (x, y))


def _overlap(fp: Footprint, pose: tuple[float, float, float], body: BodySpec) -> bool:
    """Do the footprints strictly overlap (touching is not overlapping: a robot declared
    against a wall may stay there)?"""
    other = body.footprint
    if not (isinstance(fp, Box | Cylinder) and isinstance(other, Box | Cylinder)):
        return True  # manifests hold boxes and cylinders only; anything else: keep clear
    reach = fp.circumradius() + other.circumradius()
    if abs(pose[0] - body.x) >= reach or abs(pose[1] - body.y) >= reach:
        return False  # far apart: most of a room's wall tiles, without any geometry
    if isinstance(fp, Cylinder) and isinstance(other, Cylinder):
        return math.hypot(pose[0] - body.x, pose[1] - body.y) < fp.radius + other.radius - 1e-9
    if isinstance(fp, Box) and isinstance(other, Box):
        a = _corners(fp, *pose)
        b = _corners(other, body.x, body.y, body.yaw)
        for poly in (a, b):  # separating axis theorem: the rectangles' four edge normals
            for i in range(2):
                edge = poly[i + 1] - poly[i]
                axis = np.array([-edge[1], edge[0]])
                pa, pb = a @ axis, b @ axis
                if pa.max() <= pb.min() + 1e-9 or pb.max() <= pa.min() + 1e-9:
                    return False
        return True
    if isinstance(fp, Box) and isinstance(other, Cylinder):
        return _box_circle(fp, pose, (body.x, body.y), other.radius)
    assert isinstance(fp, Cylinder) and isinstance(other, Box)
    return _box_circle(other, (body.x, body.y, body.yaw), (pose[0], pose[1]), fp.radius)


def _box_circle(box: Box, pose: tuple[float, float, float], centre: tuple[float, float],
                radius: float) -> bool:
    hx, hy = box.half_extents()
    c, s = math.cos(pose[2]), math.sin(pose[2])
    rx, ry = centre[0] - pose[0], centre[1] - pose[1]
    lx, ly = c * rx + s * ry, -s * rx + c * ry  # the circle's centre in the box's frame
    nx, ny = min(max(lx, -hx), hx), min(max(ly, -hy), hy)
    return math.hypot(lx - nx, ly - ny) < radius - 1e-9
