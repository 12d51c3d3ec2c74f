"""The pybullet world of a run: loads the generated target, steps physics, reads ground truth.

Headless (DIRECT mode), one physics client per ``BulletWorld`` so two worlds can share a
process. The plane is simulated without gravity: every movable body is driven by planar
velocities (robot: its differential-drive command; animated bodies: the animator), while
contacts between them stay real; the bodies that move besides the robot get an inertia about
their horizontal axes that no contact can turn (``keep_upright``), so none of them tips.
This module must never decide what the robot does or judge the run.
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Iterable
from pathlib import Path
from types import ModuleType
from typing import cast

import numpy as np

from rei.runtime.artifacts.world import BodySpec, WorldManifest
from rei.runtime.errors import RunError


def _import_pybullet() -> ModuleType:
    """pybullet prints its build time from C at import; keep REI's terminal output clean."""
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with open(os.devnull, "w") as devnull:
            os.dup2(devnull.fileno(), 2)
            import pybullet  # noqa: PLC0415

        # pybullet ships no type information; it is a module all the same.
        return cast(ModuleType, pybullet)
    finally:
        os.dup2(saved, 2)
        os.close(saved)


p = _import_pybullet()

CONTACT_DISTANCE = 1e-3
"""Metres: a contact point of pybullet at most this far apart is a touch."""
UPRIGHT_INERTIA = 1e9
"""kg m^2 about a moving body's horizontal axes: no contact can tip it over."""


def keep_upright(bid: int, client: int) -> None:
    """Give body ``bid`` an inertia about its horizontal axes no contact can turn (its
    inertia about the vertical axis, and so its turning in the plane, is kept)."""
    info = p.getDynamicsInfo(bid, -1, physicsClientId=client)
    # The mass is passed again: given the inertia alone, pybullet took the mass from
    # uninitialised memory (1e189 kg in one run, 1e241 kg in another), and a body that heavy
    # walked through tables, shoved the robot like a bulldozer, and was not reproducible.
    p.changeDynamics(bid, -1, mass=info[0],
                     localInertiaDiagonal=(UPRIGHT_INERTIA, UPRIGHT_INERTIA, info[2][2]),
                     physicsClientId=client)


def _quat(yaw: float) -> tuple[float, float, float, float]:
    return (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))


class BulletWorld:
    """The loaded world; call ``close`` (or use as a context manager) to free the client."""

    def __init__(self, manifest: WorldManifest, physics_rate: float) -> None:
        self.manifest = manifest
        self.dt = 1.0 / physics_rate
        self.client = p.connect(p.DIRECT)
        try:
            cid = self.client
            p.resetSimulation(physicsClientId=cid)
            p.setPhysicsEngineParameter(fixedTimeStep=self.dt, deterministicOverlappingPairs=1,
                                        numSolverIterations=10, physicsClientId=cid)
            p.setGravity(0.0, 0.0, 0.0, physicsClientId=cid)
            self.wall_ids = [self._load(b) for b in manifest.walls]
            self.object_ids = [self._load(b) for b in manifest.objects]
            self.robot_id = self._load(manifest.robot)
            # Nothing topples in REI's planar world. Velocities are set in the plane, but a
            # contact's impulse within a step still turned a person about a horizontal axis,
            # and the tilt added up: a social walker brushing a table leaned 37 degrees and
            # the top of the leaning cylinder touched a robot 0.3 m from its footprint
            # (issue 25, a 1,000-run campaign's room_0337; wp-walls saw 23 degrees).
            for bid, body in zip(self.object_ids, manifest.objects, strict=True):
                if not body.fixed:
                    keep_upright(bid, self.client)
        except Exception:
            p.disconnect(physicsClientId=self.client)
            raise
        self._names = {bid: b.name for bid, b in zip(self.wall_ids, manifest.walls, strict=False)}
        self._names.update({bid: b.name for bid, b in
                            zip(self.object_ids, manifest.objects, strict=True)})
        # The stream names bodies by their index in manifest.observed (walls, then objects),
        # which is the order of StreamHeader.objects.
        self._observed_index = {bid: i for i, bid in enumerate(self.wall_ids + self.object_ids)}
        # Bodies that move but are not animated (free dynamic objects) are kept planar after
        # every step; animated ones are driven by the animator.
        self.free_ids = [bid for bid, b in zip(self.object_ids, manifest.objects, strict=False)
                         if not b.fixed and b.trajectory is None]
        self.moving_index = [i for i, b in enumerate(manifest.objects) if not b.fixed]
        self._fixed_poses = np.array([(b.x, b.y, b.yaw) for b in manifest.objects],
                                     dtype=float).reshape(-1, 3)
        self._moving = [(i, self.object_ids[i]) for i in self.moving_index]
        self._states: tuple[np.ndarray, np.ndarray] | None = None
        """``object_states`` of the current step, until a step or a velocity change."""

    def _load(self, body: BodySpec) -> int:
        path = Path(self.manifest.folder) / body.urdf
        if not path.is_file():
            raise RunError(f"the generated world names '{body.urdf}' for '{body.name}', but "
                           f"'{path}' does not exist (regenerate the pybullet target)")
        try:
            # Every body is a single link: maximal coordinates make it a plain rigid body,
            # which steps about four times faster than a one-link multibody.
            bid: int = p.loadURDF(str(path), [body.x, body.y, body.z], _quat(body.yaw),
                             useFixedBase=body.fixed, useMaximalCoordinates=True,
                             physicsClientId=self.client)
        except p.error as exc:
            raise RunError(f"pybullet cannot load '{path}': {exc}") from None
        if not body.fixed:
            p.changeDynamics(bid, -1, linearDamping=0.0, angularDamping=0.0, lateralFriction=0.5,
                             physicsClientId=self.client)
        return bid

    def __enter__(self) -> BulletWorld:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        if self.client >= 0:
            p.disconnect(physicsClientId=self.client)
            self.client = -1

    def pose(self, bid: int) -> tuple[float, float, float]:
        pos, (x, y, z, w) = p.getBasePositionAndOrientation(bid, physicsClientId=self.client)
        # the yaw of the quaternion, inline: this runs several times per physics step
        return (pos[0], pos[1], math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)))

    def twist(self, bid: int) -> tuple[float, float, float]:
        lin, ang = p.getBaseVelocity(bid, physicsClientId=self.client)
        return (lin[0], lin[1], ang[2])

    def place(self, bid: int, pose: tuple[float, float, float]) -> None:
        """Put a body at a planar pose (tests and benchmarks; a run never teleports bodies)."""
        self._states = None
        z = p.getBasePositionAndOrientation(bid, physicsClientId=self.client)[0][2]
        p.resetBasePositionAndOrientation(bid, (pose[0], pose[1], z), _quat(pose[2]),
                                          physicsClientId=self.client)

    def set_planar_velocity(self, bid: int, vx: float, vy: float, wz: float) -> None:
        self._states = None
        p.resetBaseVelocity(bid, (vx, vy, 0.0), (0.0, 0.0, wz), physicsClientId=self.client)

    def set_planar_velocities(self, rows: Iterable[tuple[int, float, float, float]]) -> None:
        """``set_planar_velocity`` for each (body, vx, vy, wz), in order: one Python call per
        physics step for all the animated bodies rather than one per body."""
        self._states = None
        reset, cid = p.resetBaseVelocity, self.client
        for bid, vx, vy, wz in rows:
            reset(bid, (vx, vy, 0.0), (0.0, 0.0, wz), physicsClientId=cid)

    def drive_robot(self, linear: float, angular: float, yaw: float) -> None:
        """Apply a differential-drive command at the robot's heading ``yaw``."""
        self.set_planar_velocity(self.robot_id, linear * math.cos(yaw), linear * math.sin(yaw),
                                 angular)

    def step(self) -> None:
        self._states = None
        for bid in self.free_ids:
            lin, ang = p.getBaseVelocity(bid, physicsClientId=self.client)
            p.resetBaseVelocity(bid, (lin[0], lin[1], 0.0), (0.0, 0.0, ang[2]),
                                physicsClientId=self.client)
        p.stepSimulation(physicsClientId=self.client)

    def _touching(self) -> set[int]:
        """Body ids the robot touches now: a contact point closer than 1 mm (pybullet keeps
        points a little apart as well; those are not touches)."""
        points = p.getContactPoints(bodyA=self.robot_id, physicsClientId=self.client)
        return {pt[2] for pt in points if pt[8] < CONTACT_DISTANCE} if points else set()

    def robot_contacts(self) -> list[str]:
        """Names of the bodies the robot touches now (sorted)."""
        return sorted(self._names.get(bid, str(bid)) for bid in self._touching())

    def robot_contact_indices(self) -> list[int]:
        """Indices into manifest.observed (the stream's objects) of the bodies the robot
        touches now, sorted; the same test as ``robot_contacts``."""
        touching = self._touching()
        if not touching:
            return []
        index = self._observed_index
        return sorted(index[bid] for bid in touching if bid in index)

    def object_states(self) -> tuple[np.ndarray, np.ndarray]:
        """(N, 3) poses and twists of manifest.objects, in order (the caller's own arrays).

        Read once per physics step: a second call before the next step or velocity change
        (the laser and the collector at the same instant) copies the first one's."""
        if self._states is None:
            poses = self._fixed_poses.copy()
            twists = np.zeros_like(poses)
            cid = self.client
            get_pose, get_twist = p.getBasePositionAndOrientation, p.getBaseVelocity
            for i, bid in self._moving:
                pos, (x, y, z, w) = get_pose(bid, physicsClientId=cid)
                poses[i] = (pos[0], pos[1],
                            math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)))
                lin, ang = get_twist(bid, physicsClientId=cid)
                twists[i] = (lin[0], lin[1], ang[2])
            self._states = (poses, twists)
        poses, twists = self._states
        return poses.copy(), twists.copy()

    def ray_scan(self, origin: tuple[float, float, float], angles: np.ndarray,
                 max_range: float) -> np.ndarray:
        """Ranges by pybullet's own ray test (rayTestBatch), ignoring the robot itself.

        The runtime's laser is the vectorised one in rei.runtime.simulation.sensors.laser; this is
        the
        reference it is checked against, and the baseline of the benchmark.
        """
        ox, oy, oz = origin
        starts = [(ox, oy, oz)] * len(angles)
        ends = [(ox + max_range * math.cos(a), oy + max_range * math.sin(a), oz) for a in angles]
        ranges = np.full(len(angles), max_range)
        hits = p.rayTestBatch(starts, ends, numThreads=1, physicsClientId=self.client)
        for i, hit in enumerate(hits):
            if hit[0] >= 0 and hit[0] != self.robot_id:
                ranges[i] = hit[2] * max_range
        return ranges
