"""Control defects: the navigator commands motions it must not command."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from rei.runtime.robot.protocol import ControllerContext, Observation, VelocityCommand
from rei.runtime.robot.reference import ReferenceNavigator

OVERSPEED = 2.5
"""ExceedsDriveLimit believes the drive is this many times faster than it is."""
HEADING_GAIN = 3.0
"""OscillatingHeading multiplies every angular command by this."""


class ExceedsDriveLimit(ReferenceNavigator):
    """Defect: plans and commands with a top speed 2.5 times the drive's: at cruise it
    commands 1.3 to 2.5 times the drive's limit (the motor clips the command, so the robot
    itself moves much as the reference does; only the command is wrong).

    Imitates: a controller configuration copied from a faster base (`max_vel_x` of another
    robot), or a unit error in the speed limit.

    Expected catcher: SPEED_LIMIT (it judges the commanded velocity). ``check_controller``
    reports it too: "step() exceeded the drive limits".
    """

    name = "exceeds-drive-limit"

    def reset(self, context: ControllerContext) -> None:
        drive = replace(context.drive, max_linear=context.drive.max_linear * OVERSPEED)
        super().reset(replace(context, drive=drive))


class IgnoresMissionSpeed(ReferenceNavigator):
    """Defect: ignores the mission's speed limit (``max_speed``) and drives at the drive's.

    Imitates: a speed-limit parameter the stack never reads (a speed filter whose mask is not
    loaded, a parameter set in the wrong namespace).

    Expected catcher: SPEED_LIMIT; only in missions with ``max_speed`` below the drive's.
    """

    name = "ignores-mission-speed"

    def reset(self, context: ControllerContext) -> None:
        super().reset(replace(context, max_speed=None))


class NoSlowZone(ReferenceNavigator):
    """Defect: never slows down near people or unmapped obstacles (no slow zone at all).

    Imitates: a people-aware speed layer (social costmap, speed zone) that is switched off or
    never receives detections.

    Expected catcher: HUMAN_SLOW_ZONE; only in missions with humans or dynamic objects.
    """

    name = "no-slow-zone"

    def _in_slow_zone(self, pose: tuple[float, float, float], points: np.ndarray) -> bool:
        return False


class OscillatingHeading(ReferenceNavigator):
    """Defect: every angular command is three times what the planner chose (clipped to the
    drive), so the robot overshoots its heading and weaves along its path.

    Imitates: a heading gain tuned at a lower control rate or on a lighter robot.

    Expected catcher: the collision requirements (the weaving sweeps wider than planned),
    GOAL_HEADING and task time-outs.
    """

    name = "oscillating-heading"

    def step(self, observation: Observation) -> VelocityCommand:
        cmd = super().step(observation)
        w = float(np.clip(HEADING_GAIN * cmd.angular, -self._wmax, self._wmax))
        return VelocityCommand(cmd.linear, w)
