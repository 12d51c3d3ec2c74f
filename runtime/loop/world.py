"""The world component: pybullet physics and the ground truth read from it.

Every physics step it first applies what the previous tick decided (the animator's body
velocities, then the robot's motor command at its heading) and steps pybullet, then
publishes the robot's true pose and the bodies touching it. It publishes the objects'
states when a reader needs them (the laser's ticks when it sees moving bodies, the
collector's samples, the end of the run) and the animated bodies' poses every control tick.
It also counts contact episodes (a new one starts when a body starts touching the robot).
"""

from __future__ import annotations

from dataclasses import dataclass

from rei.runtime.loop.board import Board
from rei.runtime.loop.scheduler import Clock
from rei.runtime.messages import BodyStates, RobotTruth, TrackedBodies
from rei.runtime.world.bullet import BulletWorld
from rei.runtime.world.manifest import WorldManifest


@dataclass(frozen=True)
class World:
    manifest: WorldManifest
    """With the robot at its (jittered) start pose."""
    physics_rate: float
    names: tuple[str, ...]
    """Names of the stream's objects (walls, then objects), for the contact record."""
    bodies_every: tuple[int, ...]
    """Steps between the readers' needs of the objects' states (laser, collector)."""
    control_every: int

    def start(self, board: Board) -> WorldRun:
        return WorldRun(self, board)


class WorldRun:
    def __init__(self, spec: World, board: Board) -> None:
        self.spec = spec
        self.board = board
        self.world = BulletWorld(spec.manifest, spec.physics_rate)
        self.tracked: tuple[int, ...] = ()
        """pybullet ids whose poses go out every control tick (the animator's bodies)."""
        self.episodes = 0
        self.touched_names: set[str] = set()
        self.first_contact: float | None = None
        self._touching: set[str] = set()
        self._seq = [0, 0, 0]
        self._yaw = spec.manifest.robot.yaw

    def track(self, bodies: tuple[int, ...]) -> None:
        self.tracked = bodies

    def step(self, clock: Clock) -> None:
        world, board, k = self.world, self.board, clock.k
        if k > 0:
            if board.velocities is not None:
                for body, vx, vy, wz in board.velocities.velocities:
                    world.set_planar_velocity(body, vx, vy, wz)
            linear, angular = board.command.motor if board.command is not None else (0.0, 0.0)
            world.drive_robot(linear, angular, self._yaw)
            world.step()
        pose = world.pose(world.robot_id)
        self._yaw = pose[2]
        touching = world.robot_contact_indices()
        if touching or self._touching:
            self._contacts(touching, clock.now)
        board.truth = RobotTruth(self._seq[0], clock.now, pose, tuple(touching))
        self._seq[0] += 1
        if any(k % n == 0 for n in self.spec.bodies_every):
            self._bodies(clock.now)
        if self.tracked and k % self.spec.control_every == 0:
            board.tracked = TrackedBodies(self._seq[2], clock.now,
                                          tuple(world.pose(b) for b in self.tracked), pose,
                                          world.twist(world.robot_id))
            self._seq[2] += 1

    def observe(self, clock: Clock) -> None:
        """At the end of the run: the truth and the objects' states of this tick, if not
        published yet (the run may end before the first step, or off the sample rate)."""
        if self.board.truth is None:
            pose = self.world.pose(self.world.robot_id)
            self.board.truth = RobotTruth(self._seq[0], clock.now, pose,
                                          tuple(self.world.robot_contact_indices()))
            self._seq[0] += 1
        bodies = self.board.bodies
        if bodies is None or bodies.time != clock.now:
            self._bodies(clock.now)

    def _bodies(self, now: float) -> None:
        poses, twists = self.world.object_states()
        self.board.bodies = BodyStates(self._seq[1], now, self.world.twist(self.world.robot_id),
                                       poses, twists)
        self._seq[1] += 1

    def _contacts(self, touching: list[int], now: float) -> None:
        names = self.spec.names
        current = {names[i] for i in touching}
        new = current - self._touching
        if new:
            self.episodes += len(new)
            self.touched_names |= new
            if self.first_contact is None:
                self.first_contact = now
        self._touching = current

    def close(self) -> None:
        self.world.close()

