"""The world component: pybullet physics and the ground truth read from it.

Every physics step it first applies what the previous tick decided (the animator's body
velocities for that step, then the robot's motor command at its heading), steps pybullet
and notes the bodies touching the robot; at the ticks where another component reads the
truth (laser, control, sample) it publishes the robot's true pose and those bodies. It
publishes the objects' states when a reader needs them (the laser's ticks when it sees
moving bodies, the collector's samples and the end of the run, with every body touched since
the previous sample) and the animated bodies' poses every control tick. It also counts
contact episodes (a new one starts when a body starts touching the robot).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rei.runtime.artifacts.world import WorldManifest
from rei.runtime.messages import BodyStates, RobotTruth, TrackedBodies
from rei.runtime.simulation.loop.board import Board
from rei.runtime.simulation.loop.scheduler import Clock
from rei.runtime.simulation.world.bullet import BulletWorld

SAMPLE, SCAN = "sample", "scan"
"""Why the objects' states go out at a tick."""


@dataclass(frozen=True)
class World:
    manifest: WorldManifest
    """With the robot at its (jittered) start pose."""
    physics_rate: float
    names: tuple[str, ...]
    """Names of the stream's objects (walls, then objects), for the contact record."""
    laser_every: int
    """Steps between the laser's scans."""
    laser_bodies: bool
    """The laser needs the objects' states (something moving crosses its plane)."""
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
        # What goes out at each phase of the readers' common period (one look-up per step):
        # the truth when anyone reads it, the objects' states for a sample or a scan.
        self._period = math.lcm(spec.control_every, spec.sample_every, spec.laser_every)
        if self._period > 100_000:  # rates without a small common period: ask every step
            self._period = 0
        self._plan = tuple(self._plan_at(k) for k in range(self._period))

    def track(self, bodies: tuple[int, ...]) -> None:
        self.tracked = bodies

    def step(self, clock: Clock) -> None:
        world, board, k = self.world, self.board, clock.k
        if k > 0:
            velocities = board.velocities
            if velocities is not None:
                # the previous step's row: the message starts at a control tick
                row = k - 1 - round(velocities.time * self.spec.physics_rate)
                world.set_planar_velocities(velocities.steps[row])
            linear, angular = board.command.motor if board.command is not None else (0.0, 0.0)
            world.drive_robot(linear, angular, self._yaw)
            world.step()
        pose = world.pose(world.robot_id)
        self._yaw = pose[2]
        touching = world.robot_contact_indices()
        if touching or self._touching:
            self._contacts(touching, clock.now)
        truth, bodies, control = (self._plan[k % self._period] if self._period
                                  else self._plan_at(k))
        if not truth:
            return
        board.truth = RobotTruth(self._truth_seq, clock.now, pose, tuple(touching))
        self._truth_seq += 1
        if bodies is not None:
            self._bodies(clock.now, sample=bodies is SAMPLE)
        if self.tracked and control:
            board.tracked = TrackedBodies(self._tracked_seq, clock.now,
                                          tuple(world.pose(b) for b in self.tracked), pose,
                                          world.twist(world.robot_id))
            self._tracked_seq += 1

    def _plan_at(self, k: int) -> tuple[bool, str | None, bool]:
        """At tick ``k``: publish the truth? the objects' states (for what)? the tracked?"""
        spec = self.spec
        control, sample, laser = spec.control_every, spec.sample_every, spec.laser_every
        bodies = SAMPLE if k % sample == 0 else \
            SCAN if spec.laser_bodies and k % laser == 0 else None
        return (k % control == 0 or k % sample == 0 or k % laser == 0, bodies,
                k % control == 0)

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

