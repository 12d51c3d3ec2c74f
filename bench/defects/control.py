"""Control defects: the navigator commands motions it must not command."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from rei.runtime.messages import NavState
from rei.runtime.robot.contract import ControllerContext, Observation, VelocityCommand
from rei.runtime.robot.navigator.recovery import motion_is_safe
from rei.runtime.robot.navigator.reference import ReferenceNavigator

OVERSPEED = 2.5
"""ExceedsDriveLimit believes the drive is this many times faster than it is."""
HEADING_GAIN = 3.0
"""OscillatingHeading multiplies every angular command by this."""
APPROACH_DISTANCE = 0.6
"""Metres: InvertedApproachScaling scales its speed by this over the distance to the goal."""
MIN_APPROACH_SPEED = 0.05
"""m/s below which InvertedApproachScaling does not scale (Nav2's default minimum approach
speed)."""
PROGRESS_RADIUS = 0.05
"""Metres SpinsWhenTurning's progress checker wants the robot to move within its allowance."""
PROGRESS_ALLOWANCE = 1.0
"""Seconds SpinsWhenTurning's progress checker allows without that much translation."""
CLEARING_SPIN = 2 * math.pi
"""Radians of SpinsWhenTurning's clearing rotation."""


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

    Expected catcher: SMOOTH_MOTION where the route makes it steer while driving (round
    furniture, through a bend). On a straight route it has nothing to amplify (three times
    no turn is no turn) and passes; GOAL_HEADING cannot see it, since its goal check still
    ends a goal only within 0.05 rad of the heading (bench/RESULTS.md, "oscillating-heading
    on seed 1").
    """

    name = "oscillating-heading"

    def step(self, observation: Observation) -> VelocityCommand:
        cmd = super().step(observation)
        w = float(np.clip(HEADING_GAIN * cmd.angular, -self._wmax, self._wmax))
        return VelocityCommand(cmd.linear, w)


class InvertedApproachScaling(ReferenceNavigator):
    """Defect: the approach speed scaling is inverted: instead of slowing down by
    ``remaining / 0.6 m`` on its last 0.6 m, it scales every command by ``0.6 m / remaining``
    (never below 0.05 m/s, Nav2's minimum approach speed), so it crawls while the goal is far
    (0.05 m/s beyond ~3 m) and gets up to speed only as it nears it.

    Imitates: an approach-velocity-scaling ratio written upside down (Regulated Pure
    Pursuit's scaling by the remaining path over ``approach_velocity_scaling_dist``).

    Expected catcher: TIME_TO_GOAL on tasks of a few metres; task time-outs
    (MISSION_GOALS_REACHED) on long ones, where the crawl outlasts the goal's timeout first.
    """

    name = "inverted-approach-scaling"

    def step(self, observation: Observation) -> VelocityCommand:
        cmd = super().step(observation)
        goal = self._tracker.goal
        if goal is None or cmd.linear <= MIN_APPROACH_SPEED:
            return cmd
        x, y, _ = observation.odom_pose
        remaining = math.hypot(goal.x - x, goal.y - y)
        scale = max(min(1.0, APPROACH_DISTANCE / max(remaining, 1e-6)),
                    MIN_APPROACH_SPEED / cmd.linear)
        # Scaling both keeps the arc the local planner checked against the laser.
        return VelocityCommand(cmd.linear * scale, cmd.angular * scale)


class SpinsWhenTurning(ReferenceNavigator):
    """Defect: a progress checker that counts translation only: when the robot has not moved
    5 cm for a second, it declares the goal stuck and runs a clearing rotation (a full turn
    on the spot, when the laser shows room for it) before going on. Turning on the spot to a
    goal's heading, or to face the goal at the end of the approach, is no progress to it, so
    the robot spins a full turn at goals where that turn lasts more than a second.

    Imitates: a translation-only progress checker (Nav2's SimpleProgressChecker, which
    ignores rotation; PoseProgressChecker was added for this) with a short movement time
    allowance, and a recovery tree that spins first.

    Expected catcher: NO_SPIN_AT_GOAL (a full turn plus the turn to the heading is more than
    its 4.7 rad); mostly at goals with a heading.
    """

    name = "spins-when-turning"

    def reset(self, context: ControllerContext) -> None:
        super().reset(context)
        self._checkpoint: tuple[float, float, float] | None = None
        self._spun: float | None = None
        """Radians of the running clearing rotation (None: none running)."""
        self._last_yaw = 0.0

    def step(self, observation: Observation) -> VelocityCommand:
        x, y, yaw = observation.odom_pose
        now = observation.time
        if self._tracker.state != NavState.ACTIVE:
            self._checkpoint, self._spun = None, None
            return super().step(observation)
        if self._spun is not None:
            self._spun += abs(math.remainder(yaw - self._last_yaw, math.tau))
            self._last_yaw = yaw
            w = 0.5 * self._wmax
            if self._spun < CLEARING_SPIN and motion_is_safe(
                    self._laser_points(observation), self._half, 0.0, w):
                return VelocityCommand(0.0, w)
            self._spun, self._checkpoint = None, (x, y, now)  # the recovery is over
        checkpoint = self._checkpoint
        if checkpoint is None or math.hypot(x - checkpoint[0], y - checkpoint[1]) > \
                PROGRESS_RADIUS:
            self._checkpoint = (x, y, now)
        elif now - checkpoint[2] > PROGRESS_ALLOWANCE and motion_is_safe(
                self._laser_points(observation), self._half, 0.0, 0.5 * self._wmax):
            self._spun, self._last_yaw = 0.0, yaw
            return VelocityCommand(0.0, 0.5 * self._wmax)
        return super().step(observation)
