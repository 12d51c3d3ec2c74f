"""The world component: pybullet physics and the ground truth read from it.

Every physics step it first applies what the previous tick decided (the animator's body
velocities for that step, then the robot's motor command at its heading) and steps pybullet,
then
publishes the robot's true pose and the bodies touching it. It publishes the objects'
states when a reader needs them (the laser's ticks when it sees moving bodies, the
collector's samples and the end of the run, with every body touched since the previous
sample) and the animated bodies' poses every control tick.
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
    laser_every: int | None
    """Steps between the laser's scans when it needs the objects' states (None: it never
    does: nothing moving crosses its plane)."""
    sample_every: int
    """Steps between the collector's samples."""
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
        self._truth_seq = self._bodies_seq = self._tracked_seq = 0
        self._yaw = spec.manifest.robot.yaw
        self._touched: set[int] = set()
        """Bodies touched since the previous sample."""
        self._sampled: float | None = None
        """When the latest states for a sample went out."""

    def track(self, bodies: tuple[int, ...]) -> None:
        self.tracked = bodies

    def step(self, clock: Clock) -> None:
        world, board, k = self.world, self.board, clock.k
        if k > 0:
            velocities = board.velocities
            if velocities is not None:
                # the previous step's row: the message starts at a control tick
                row = k - 1 - round(velocities.time * self.spec.physics_rate)
                for body, vx, vy, wz in velocities.steps[row]:
                    world.set_planar_velocity(body, vx, vy, wz)
            linear, angular = board.command.motor if board.command is not None else (0.0, 0.0)
            world.drive_robot(linear, angular, self._yaw)
            world.step()
        pose = world.pose(world.robot_id)
        self._yaw = pose[2]
        touching = world.robot_contact_indices()
        if touching or self._touching:
            self._contacts(touching, clock.now)
        board.truth = RobotTruth(self._truth_seq, clock.now, pose, tuple(touching))
        self._truth_seq += 1
        spec = self.spec
        if k % spec.sample_every == 0:
            self._bodies(clock.now, sample=True)
        elif spec.laser_every is not None and k % spec.laser_every == 0:
            self._bodies(clock.now, sample=False)
        if self.tracked and k % self.spec.control_every == 0:
            board.tracked = TrackedBodies(self._tracked_seq, clock.now,
                                          tuple(world.pose(b) for b in self.tracked), pose,
                                          world.twist(world.robot_id))
            self._tracked_seq += 1

    def observe(self, clock: Clock) -> None:
        """At the end of the run: the truth and the objects' states of this tick, if not
        published yet (the run may end before the first step, off the sample rate, or be
        interrupted within a step)."""
        truth = self.board.truth
        if truth is None or truth.time != clock.now:
            pose = self.world.pose(self.world.robot_id)
            self.board.truth = RobotTruth(self._truth_seq, clock.now, pose,
                                          tuple(self.world.robot_contact_indices()))
            self._truth_seq += 1
        if self._sampled != clock.now:
            self._bodies(clock.now, sample=True)

    def _bodies(self, now: float, sample: bool) -> None:
        poses, twists = self.world.object_states()
        touched: tuple[int, ...] = ()
        if sample:
            self._sampled = now
            if self._touched:
                touched = tuple(sorted(self._touched))
                self._touched = set()
        twist = self.world.twist(self.world.robot_id)
        self.board.bodies = BodyStates(self._bodies_seq, now, twist, poses, twists, touched)
        self._bodies_seq += 1

    def _contacts(self, touching: list[int], now: float) -> None:
        self._touched.update(touching)
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

