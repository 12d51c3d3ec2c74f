"""Mission-logic defects: the navigator's goal handling lies or gives up."""

from __future__ import annotations

import math
from dataclasses import replace

from rei.runtime.messages import NavState
from rei.runtime.robot.contract import (
    STOP,
    ControllerContext,
    GoalTracker,
    NavGoal,
    Observation,
    VelocityCommand,
)
from rei.runtime.robot.navigator.reference import ReferenceNavigator

EARLY = 0.5
"""Metres from its goal at which ClaimsSuccessEarly reports success."""


class IgnoresGoalHeading(ReferenceNavigator):
    """Defect: ignores the goal's heading and ends at the goal position with any yaw.

    Imitates: a goal message whose orientation is dropped on the way (a conversion that keeps
    only x and y, a goal checker without a yaw tolerance).

    Expected catcher: GOAL_HEADING; only in missions whose goals have a heading.
    """

    name = "ignores-goal-heading"

    def send_goal(self, goal: NavGoal) -> None:
        super().send_goal(replace(goal, yaw=None))


class AbortsEveryGoal(ReferenceNavigator):
    """Defect: accepts every goal and aborts it at once, standing still.

    Imitates: a planner that finds no path anywhere (a costmap in millimetres where metres
    were expected marks every cell lethal).

    Expected catcher: MISSION_GOALS_REACHED / task failures (every task aborted),
    MISSION_SEQUENCE.
    """

    name = "aborts-every-goal"

    def step(self, observation: Observation) -> VelocityCommand:
        if self._tracker.state == NavState.PENDING:
            self._tracker.accept()
            self._tracker.abort("no valid plan")
        return super().step(observation)


class ClaimsSuccessEarly(ReferenceNavigator):
    """Defect: reports a goal SUCCEEDED and stops as soon as it is within 0.5 m of it.

    Imitates: a goal checker with a looser xy tolerance than the mission asks (a default of
    another robot's configuration).

    Expected catcher: MISSION_GOALS_REACHED / task failures ("outside tolerance").
    """

    name = "claims-success-early"

    def step(self, observation: Observation) -> VelocityCommand:
        cmd = super().step(observation)
        tracker, goal = self._tracker, self._tracker.goal
        if tracker.state == NavState.ACTIVE and goal is not None:
            x, y, _ = observation.odom_pose
            if math.hypot(goal.x - x, goal.y - y) <= EARLY:
                tracker.succeed("within the goal checker's tolerance")
                return STOP
        return cmd


class _SilentTracker(GoalTracker):
    """A goal tracker whose success is never published."""

    def succeed(self, message: str = "") -> None:
        pass


class NeverReportsSuccess(ReferenceNavigator):
    """Defect: arrives at its goals but never reports them SUCCEEDED: the goal stays ACTIVE
    until the mission's time-out.

    Imitates: an action server whose result is never sent (the succeed call in a branch that
    is never reached, a result published on the wrong topic).

    Expected catcher: task time-outs / MISSION_GOALS_REACHED, MISSION_SEQUENCE (feedback about
    all goals). ``check_controller`` reports it too: a goal 1 m ahead "did not end".
    """

    name = "never-reports-success"

    def reset(self, context: ControllerContext) -> None:
        super().reset(context)
        self._tracker = _SilentTracker()


class SkipsSecondGoal(ReferenceNavigator):
    """Defect: reports the second goal after a reset SUCCEEDED at once, without going there.

    Imitates: a waypoint follower that drops a goal arriving while the previous result is
    being published (a race), or de-duplicates goals by name.

    Expected catcher: MISSION_GOALS_REACHED / task failures ("outside tolerance").
    """

    name = "skips-second-goal"

    def reset(self, context: ControllerContext) -> None:
        super().reset(context)
        self._goals_sent = 0

    def send_goal(self, goal: NavGoal) -> None:
        super().send_goal(goal)
        self._goals_sent += 1

    def step(self, observation: Observation) -> VelocityCommand:
        if self._goals_sent == 2 and self._tracker.state == NavState.PENDING:
            self._tracker.accept()
            self._tracker.succeed("already there")
        return super().step(observation)
