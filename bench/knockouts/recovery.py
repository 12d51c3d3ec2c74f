"""Knock-out of the recovery behaviours: the navigator gives a goal up where it would recover.

It sees recoveries the only way a wrapper can, in the navigator's feedback: while a goal is
active a navigator may report what it is doing as ``doing: recovery.backup, ...``
(rei.runtime.robot.behaviours). On a navigator that reports nothing it is its base.
"""

from __future__ import annotations

from bench.knockouts.wrapper import Wrapper
from rei.runtime.messages import NavState
from rei.runtime.robot.behaviours import reported
from rei.runtime.robot.contract import (
    STOP,
    Controller,
    ControllerContext,
    NavGoal,
    Observation,
    VelocityCommand,
)

RECOVERY = "recovery."
"""Prefix of the behaviours that are recoveries (behaviours.BEHAVIOURS)."""


class AbortsRecovery(Wrapper):
    """Defect: the goal is ABORTED (the robot stops) the moment the navigator starts its
    ``at_round``-th recovery round of the goal; the rounds before run as usual. A round is a
    stretch of consecutive ticks in which the navigator's feedback reports a ``recovery.*``
    behaviour: round 1 means no recovery ever runs.

    Graded by the round, not by the kind of recovery: the kinds a navigator has are its own
    (a wrapper cannot switch one off without reaching inside), while every navigator with a
    recovery ladder has rounds, and a shorter ladder is the real defect (Nav2's
    ``number_of_retries`` set too low, move_base's ``recovery_behavior_enabled`` false).

    Imitates: a behaviour tree or recovery list left short or empty, a retry count of zero.

    Expected catcher: task failures (MISSION_GOALS_REACHED, a task "aborted") in missions
    where the navigator needs that many recovery rounds: a person standing on the route, a
    passage it must back out of, an obstacle the map does not show.
    """

    def __init__(self, name: str, inner: Controller, at_round: int) -> None:
        super().__init__(name, inner)
        self.abort_at = at_round
        self._rounds = 0
        self._recovering = False

    def reset(self, context: ControllerContext) -> None:
        self._rounds, self._recovering = 0, False
        super().reset(context)

    def send_goal(self, goal: NavGoal) -> None:
        self._rounds, self._recovering = 0, False
        super().send_goal(goal)

    def step(self, observation: Observation) -> VelocityCommand:
        command = super().step(observation)
        if self._ended is not None:
            return command
        feedback = self.inner.feedback()
        kinds = [n for n in reported(feedback.message) if n.startswith(RECOVERY)]
        if feedback.state != NavState.ACTIVE or not kinds:
            self._recovering = False
            return command
        if not self._recovering:
            self._rounds += 1
            self._recovering = True
        if self._rounds < self.abort_at:
            return command
        self.end_goal(NavState.ABORTED,
                      f"recovery disabled: aborted where recovery round {self._rounds} "
                      f"({', '.join(kinds)}) would start")
        return STOP
