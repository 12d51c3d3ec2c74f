"""The animator component: humans and dynamic objects moving along their trajectories
(``rei.runtime.simulation.animator``), on the physics clock.

Every control tick (after the robot and the collector) it corrects its bodies' velocities
from their true poses and the robot's (the world's ``TrackedBodies``) and publishes the
velocities they take at each physics step until the next control tick (between two
corrections nothing else changes them, so they are computed together: one message, and one
stage, per control period rather than per step). Each body's start delay and speed
scale are drawn from the run's seed (their own stream) unless the run walks every
trajectory exactly as written.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rei.runtime.artifacts.world import WorldManifest
from rei.runtime.messages import BodyVelocities
from rei.runtime.simulation.animator import Animator
from rei.runtime.simulation.animator.bodies import animated_bodies, variations_record, wall_boxes
from rei.runtime.simulation.loop.board import Board
from rei.runtime.simulation.loop.scheduler import Clock


@dataclass(frozen=True)
class Humans:
    manifest: WorldManifest
    physics_rate: float
    control_every: int
    seed: int
    vary: bool

    def start(self, board: Board, object_ids: list[int]) -> HumansRun:
        """``object_ids``: the pybullet ids of the manifest's objects, in order."""
        return HumansRun(self, board, object_ids)


class HumansRun:
    def __init__(self, spec: Humans, board: Board, object_ids: list[int]) -> None:
        self.spec, self.board = spec, board
        self.named = animated_bodies(spec.manifest.objects, object_ids, spec.seed, spec.vary)
        self.items = [a for _, a in self.named]
        self.bodies = tuple(item.body for item in self.items)
        """pybullet ids of the animated bodies, in the order ``TrackedBodies`` carries."""
        fixed = spec.manifest.walls + tuple(o for o in spec.manifest.objects if o.fixed)
        self.paths = Animator(self.items, spec.physics_rate,
                           spec.manifest.robot.footprint.circumradius(),
                           walls=wall_boxes(fixed))
        self._seq = 0

    def step(self, clock: Clock) -> None:
        k = clock.k
        tracked = self.board.tracked
        assert tracked is not None and tracked.time == clock.now
        self.paths.correct(k, list(tracked.poses), tracked.robot_pose, tracked.robot_twist)
        commands = self.paths.commands
        self.board.velocities = BodyVelocities(
            self._seq, clock.now,
            tuple(tuple(commands(j)) for j in range(k, k + self.spec.control_every)))
        self._seq += 1

    def variations(self) -> dict[str, dict[str, Any]]:
        """Each body's drawn start delay and speed scale, for the run's measurements, and
        when a triggered body's clock started (None: its trigger never met)."""
        record = variations_record(self.named)
        for k, (name, item) in enumerate(self.named):
            if item.start_when is not None and name in record:
                record[name]["started_s"] = self.paths.started_at(k)
        return record
