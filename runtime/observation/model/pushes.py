"""The robot's own motion apart from motion a contact gave it (``PushTracker``).

A body that walks into a standing robot shoves it, and requirements on driven motion must not
blame the robot for that speed: this module tells the two apart, sample by sample, from the
speeds, the command, the contacts and the approach speeds the runtime model hands it. It must
never import pybullet, the simulation, the evaluator or the monitor's host.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

PUSH_CONTACT = 0.02
"""m: a footprint distance below this (or a physical contact) is a contact for the push
attribution (the default .vepl's eps_collision)."""
PUSH_APPROACH = 0.01
"""m/s: a contact while the robot's own command closes in faster than this is the robot's
doing (the default .vepl's v_contact), so it never starts a push."""
PUSH_SLACK = 0.02
"""m/s: the robot moves beyond its command when its speed exceeds the command by more."""
PUSH_TURN_SLACK = 0.05
"""rad/s: likewise for turning (the default .vepl's turn_tolerance)."""


@dataclass(frozen=True)
class OwnMotion:
    """The robot's driven motion it answers for, and whether it was being pushed."""

    speed: float
    yaw_rate: float
    pushed: bool


@dataclass
class PushTracker:
    """Tells motion the robot commanded from motion a contact it did not drive into gave it.

    A push starts at a contact (physical, or footprints within ``PUSH_CONTACT``) while the
    robot's own command does not close in on anything it touches (every ``approach`` at most
    ``PUSH_APPROACH``): a person walking into a standing robot, a cart rolling into it. It
    lasts while the contact does, and after it while the robot still moves beyond its
    command (the shove's momentum); a contact the robot drives into ends it. While pushed, the
    robot's own speed is its ground-truth speed capped at its commanded speed, and its own
    turn rate the ground truth clamped between 0 and its commanded turn rate: a shoved robot
    answers for what it commanded, never for more, and never for less. Outside a push, its
    own motion is the ground truth.
    """

    active: bool = False

    def update(self, speed: float, yaw_rate: float, cmd: tuple[float, float],
               contact: np.ndarray, approach: np.ndarray) -> OwnMotion:
        v = abs(cmd[0])
        low, high = min(0.0, cmd[1]), max(0.0, cmd[1])
        own_yaw = min(max(yaw_rate, low), high)
        beyond = speed > v + PUSH_SLACK or abs(yaw_rate - own_yaw) > PUSH_TURN_SLACK
        if contact.any():
            self.active = not bool((approach[contact] > PUSH_APPROACH).any())
        elif not beyond:
            self.active = False
        pushed = self.active and beyond
        if not pushed:
            return OwnMotion(speed, yaw_rate, False)
        return OwnMotion(min(speed, v), own_yaw, True)
