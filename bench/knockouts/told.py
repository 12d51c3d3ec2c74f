"""Knock-outs in what the navigator is told: its footprint, a goal's tolerance, the mission's
speed limit. The navigator itself is sound; its configuration is wrong by a graded factor."""

from __future__ import annotations

import math
from dataclasses import replace

from bench.knockouts.wrapper import Wrapper
from rei.runtime.messages import NavState
from rei.runtime.robot.contract import (
    Controller,
    ControllerContext,
    NavGoal,
    Observation,
    VelocityCommand,
)


class Footprint(Wrapper):
    """Defect: the navigator is told the robot is ``percent`` % of its real size (both sides
    of the footprint box scaled), so it plans through gaps the robot does not fit and keeps
    its margins from a footprint that is not the robot's.

    Imitates: a footprint or robot radius copied from another robot's configuration (a
    TurtleBot's parameters on a larger base), or given in the wrong unit or as half sizes.

    Expected catcher: the collision requirements (NO_ROBOT_COLLISION,
    GEOM_COLLISION_LASER_CORRECT, MISSION_SIMPLE) in passages narrower than the robot plus its
    margins but wider than the believed footprint; task failures when it wedges itself.
    """

    def __init__(self, name: str, inner: Controller, percent: int) -> None:
        super().__init__(name, inner)
        self.scale = percent / 100

    def reset(self, context: ControllerContext) -> None:
        sx, sy = context.robot_size
        super().reset(replace(context, robot_size=(sx * self.scale, sy * self.scale)))


class GoalTolerance(Wrapper):
    """Defect: the navigator's goal tolerance is ``percent`` % of the goal's. It is sent each
    goal with the tolerance scaled, and its goal checker (this wrapper, as Nav2's
    ``SimpleGoalChecker`` would with a wrong ``xy_goal_tolerance``) reports a goal without a
    heading SUCCEEDED and stops as soon as odometry puts the robot within the scaled tolerance
    of it. The checker is the wrapper's so the defect shows whatever margin the wrapped
    navigator keeps below the tolerance it is told (the reference aims at 0.1 m at most, so
    passing it the scaled goal alone changes nothing for tolerances of 0.2 m and more). Goals
    with a heading are left to the navigator, told the scaled tolerance: ending one early would
    add a second defect, the heading never turned to.

    Imitates: ``xy_goal_tolerance`` set for another robot or task (docking vs. delivery), or a
    tolerance given as a diameter where a radius was meant.

    Expected catcher: MISSION_GOALS_REACHED (a task "outside tolerance") when the robot stops
    farther from a goal than its tolerance.
    """

    def __init__(self, name: str, inner: Controller, percent: int) -> None:
        super().__init__(name, inner)
        self.scale = percent / 100

    def send_goal(self, goal: NavGoal) -> None:
        super().send_goal(replace(goal, tolerance=goal.tolerance * self.scale))

    def step(self, observation: Observation) -> VelocityCommand:
        goal = self._goal
        if (self._ended is None and goal is not None and goal.yaw is None
                and self.inner.feedback().state == NavState.ACTIVE):
            x, y, _ = observation.odom_pose
            distance = math.hypot(goal.x - x, goal.y - y)
            if distance <= goal.tolerance:  # the scaled one: what the navigator was sent
                self.end_goal(NavState.SUCCEEDED, "", distance)
        return super().step(observation)


class SpeedLimit(Wrapper):
    """Defect: the navigator is told the mission's speed limit ``percent`` % higher than it
    is (missions without a limit are unchanged; the drive's own limit is never changed:
    exceeding that is a separate defect, bench/defects' exceeds-drive-limit, and the base
    clips it anyway).

    Imitates: a speed limit applied after a unit or rounding error, or a velocity smoother's
    limit set above the zone's limit "to leave some headroom".

    Expected catcher: SPEED_LIMIT in missions with a speed
    limit below the drive's; nothing elsewhere, where the knock-out is its base.
    """

    def __init__(self, name: str, inner: Controller, percent: int) -> None:
        super().__init__(name, inner)
        self.scale = 1 + percent / 100

    def reset(self, context: ControllerContext) -> None:
        limit = context.max_speed
        super().reset(context if limit is None
                      else replace(context, max_speed=limit * self.scale))
