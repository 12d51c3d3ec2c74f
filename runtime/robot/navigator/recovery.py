"""Recovery behaviours of the `reference` navigator, as a real navigation stack has them.

When the local planner finds no admissible motion, or the robot makes no progress, ROS
move_base / Nav2 do not give up at once: they back up a little, rotate in place, clear the
costmap and re-plan, and wait, escalating through a ladder of such behaviours before
declaring the goal failed. ``Recovery`` is that ladder for ``ReferenceNavigator``:

* level 0: re-plan around what the laser sees now, back up, turn towards the path;
* level 1: re-plan around what the laser sees with the footprint inflation reduced to
  the robot's half width (passages only an aligned robot fits), back up, turn;
* level 2: wait (a person in the way may walk on), re-plan around the laser, turn.

Re-planning comes before backing up, where the robot got stuck: a new path is measured
from there, so driving back to that spot is no progress (only getting past it is).

Every motion of a behaviour is checked against the laser points with the exact rectangular
footprint over a short horizon (``motion_is_safe``), at the drive limits' fractions given
here: a behaviour that cannot move safely ends and the ladder goes on. Time is the
observation's simulated time, never the wall clock; there is no randomness.
This module must never import pybullet, and never command a motion it has not checked.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from rei.runtime.robot.contract import STOP, VelocityCommand
from rei.runtime.robot.navigator.clearance import box_distance

RECOVERY_MARGIN = 0.015
"""Metres the exact footprint keeps from every laser point during a recovery motion."""
CHECK_HORIZON = 0.5
"""Seconds each recovery command is checked ahead (five control periods at 10 Hz)."""
BACKUP_DISTANCE = 0.15
BACKUP_SPEED = 0.1
"""m/s backwards (at most the drive limit): slow, as the laser sees less well behind."""
BACKUP_TIME = 4.0
SPIN_FRACTION = 0.5
"""Fraction of the drive's angular limit used to turn in place."""
SPIN_ALIGNED = 0.25
"""Radians from the path direction at which a spin ends."""
WAIT_TIME = 5.0
LEVELS: tuple[tuple[str, ...], ...] = (
    ("replan", "backup", "spin"),
    ("replan_reduced", "backup", "spin"),
    ("wait", "replan", "spin"),
)
"""The behaviours of each level, in order (Nav2's default tree clears, spins, waits, backs up)."""


def footprint_gaps(points: np.ndarray, half: tuple[float, float],
                   poses: np.ndarray) -> np.ndarray:
    """Signed distance (S, N) from each point (N, 2; robot frame now) to the rectangle of
    half sizes ``half`` centred at each pose (S, 3; robot frame now); negative inside."""
    hx, hy = half
    dx = points[None, :, 0] - poses[:, 0:1]
    dy = points[None, :, 1] - poses[:, 1:2]
    return box_distance(dx, dy, np.cos(poses[:, 2:3]), np.sin(poses[:, 2:3]), hx, hy)


def arc_poses(v: float, w: float, horizon: float, steps: int) -> np.ndarray:
    """Poses (steps + 1, 3) of a unicycle driving (v, w) from the origin for ``horizon`` s."""
    ts = np.linspace(0.0, horizon, steps + 1)
    th = w * ts
    if abs(w) < 1e-9:
        return np.stack((v * ts, np.zeros_like(ts), th), axis=1)
    return np.stack((v / w * np.sin(th), v / w * (1 - np.cos(th)), th), axis=1)


def motion_is_safe(points: np.ndarray, half: tuple[float, float], v: float, w: float,
                   horizon: float = CHECK_HORIZON, margin: float = RECOVERY_MARGIN) -> bool:
    """Whether driving (v, w) for ``horizon`` keeps the footprint ``margin`` from every point.

    A point already nearer than ``margin`` (the robot was pushed or the laser saw it late)
    must not get any nearer, so a motion away from it stays possible.
    """
    if not len(points):
        return True
    # Steps fine enough that the footprint moves at most ~1 cm (or 0.02 rad) between them.
    steps = max(2, int(math.ceil(max(abs(v) * horizon / 0.01, abs(w) * horizon / 0.02))))
    return poses_keep_clear(points, half, arc_poses(v, w, horizon, steps), margin)


def poses_keep_clear(points: np.ndarray, half: tuple[float, float], poses: np.ndarray,
                     margin: float) -> bool:
    """Whether the footprint (half sizes ``half``) at each of ``poses`` (S, 3; robot frame
    now, the first the robot's own) keeps ``margin`` from every point (N, 2); a point already
    nearer than ``margin`` must not come any nearer, so a motion away from it stays possible."""
    if not len(points):
        return True
    gaps = footprint_gaps(points, half, poses)
    floor = np.minimum(gaps[0], margin) - 1e-4
    return bool((gaps.min(axis=0) >= floor).all())


@dataclass(frozen=True)
class RecoveryAction:
    """What a recovery step wants: a command, or None when the ladder's current level is over."""

    command: VelocityCommand | None


class Recovery:
    """The ladder of recovery behaviours for one goal (deterministic; simulated time only)."""

    def __init__(self, half: tuple[float, float], vmax: float, wmax: float,
                 rear_visible: bool) -> None:
        self._half = half
        self._vback = min(BACKUP_SPEED, vmax)
        self._wspin = SPIN_FRACTION * wmax
        self._rear_visible = rear_visible
        self.reset()

    def reset(self) -> None:
        """A new goal: back to the first level, nothing running."""
        self.level = 0
        self.rounds = 0
        """Levels run since the last progress."""
        self.active = False
        self.ended_at: float | None = None
        self.log: list[str] = []
        """Behaviours begun, in order (read by tests and the feedback message)."""
        self._steps: tuple[str, ...] = ()
        self._phase = -1
        self._phase_start = 0.0
        self._origin: tuple[float, float, float] = (0.0, 0.0, 0.0)
        self._spin_dir = 0.0
        self._spin_switched = False

    @property
    def exhausted(self) -> bool:
        """Every level has run since the last progress (and none is running now)."""
        return self.rounds >= len(LEVELS) and not self.active

    def progress(self) -> None:
        """The robot made progress: the next trouble starts the ladder from the bottom."""
        if not self.active:
            self.level = 0
            self.rounds = 0

    def begin(self, time: float, pose: tuple[float, float, float]) -> None:
        """Start the next level of the ladder (wrapping round after the last)."""
        self._steps = LEVELS[self.level % len(LEVELS)]
        self.level = (self.level + 1) % len(LEVELS)
        self.rounds += 1
        self.active = True
        self._phase = -1
        self._next(time, pose)

    def _next(self, time: float, pose: tuple[float, float, float]) -> None:
        self._phase += 1
        self._phase_start = time
        self._origin = pose
        self._spin_dir = 0.0
        self._spin_switched = False
        if self._phase < len(self._steps):
            self.log.append(self._steps[self._phase])
        else:
            self.active = False
            self.ended_at = time

    def step(self, time: float, pose: tuple[float, float, float], points: np.ndarray,
             replan: Callable[[bool], bool],
             path_heading: Callable[[], float | None]) -> RecoveryAction:
        """The command of the running behaviour; ``replan(reduced)`` re-plans around the
        laser (True when a path was found), ``path_heading()`` is the world direction the
        robot should face to follow its path (None when there is none)."""
        while self.active:
            behaviour = self._steps[self._phase]
            cmd: VelocityCommand | None
            if behaviour == "backup":
                cmd = self._backup(time, pose, points)
            elif behaviour == "spin":
                cmd = self._spin(time, pose, points, path_heading())
            elif behaviour == "wait":
                cmd = STOP if time - self._phase_start < WAIT_TIME else None
            else:
                replan(behaviour == "replan_reduced")
                cmd = None
            if cmd is not None:
                return RecoveryAction(cmd)
            self._next(time, pose)
        return RecoveryAction(None)

    def _backup(self, time: float, pose: tuple[float, float, float],
                points: np.ndarray) -> VelocityCommand | None:
        if not self._rear_visible or self._vback <= 0:
            return None  # never reverse blind
        moved = math.hypot(pose[0] - self._origin[0], pose[1] - self._origin[1])
        if moved >= BACKUP_DISTANCE or time - self._phase_start >= BACKUP_TIME:
            return None
        # Straight back first; gentle backward arcs when something is right behind a corner.
        for w in (0.0, 0.5 * self._wspin, -0.5 * self._wspin):
            if motion_is_safe(points, self._half, -self._vback, w):
                return VelocityCommand(-self._vback, w)
        return None

    def _spin(self, time: float, pose: tuple[float, float, float], points: np.ndarray,
              heading: float | None) -> VelocityCommand | None:
        # Turning a full circle takes 2 pi / w; beyond that the spin has seen everything.
        if time - self._phase_start >= math.tau / self._wspin + 1.0:
            return None
        if heading is None:
            err = math.pi  # nothing to face: turn round once to look
        else:
            err = math.remainder(heading - pose[2], math.tau)
            if abs(err) < SPIN_ALIGNED:
                return None
        if self._spin_dir == 0.0:
            self._spin_dir = 1.0 if err >= 0 else -1.0
        w = self._spin_dir * min(self._wspin, max(0.3, 1.5 * abs(err)))
        if motion_is_safe(points, self._half, 0.0, w):
            return VelocityCommand(0.0, w)
        if not self._spin_switched:
            # Blocked one way: the long way round may be free.
            self._spin_switched = True
            self._spin_dir = -self._spin_dir
            w = -w
            if motion_is_safe(points, self._half, 0.0, w):
                return VelocityCommand(0.0, w)
        return None
