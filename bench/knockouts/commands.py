"""Knock-outs between the navigator and the base: its commands arrive late, or some of them
never arrive. The navigator decides as it always does, unaware; time is the observation's
clock, chance is drawn from the run's seed, one number per control tick."""

from __future__ import annotations

from collections import deque

import numpy as np

from bench.knockouts.wrapper import Wrapper, seeded
from rei.runtime.robot.contract import (
    STOP,
    Controller,
    ControllerContext,
    Observation,
    VelocityCommand,
)

SAME_TICK = 1e-9
"""Seconds of float rounding within which two observation times are the same instant."""


class Delay(Wrapper):
    """Defect: every command reaches the base ``milliseconds`` ms after the navigator gave it
    (the command of the last tick at least that old; ``STOP`` until the first one is).

    Imitates: a command path through a congested network or a deep queue (a ``cmd_vel`` relay
    with a large buffer, a velocity smoother with a long window, a base driver polled slowly).

    Expected catcher: REACTION_TIME (it slows that much later after its laser showed a
    person or a moving object ahead), HUMAN_SLOW_ZONE, the collision requirements
    (overshooting into obstacles), SMOOTH_MOTION and task failures from overshot goals.
    """

    def __init__(self, name: str, inner: Controller, milliseconds: int) -> None:
        super().__init__(name, inner)
        self.delay = milliseconds / 1000
        self._queue: deque[tuple[float, VelocityCommand]] = deque()
        self._released = STOP

    def reset(self, context: ControllerContext) -> None:
        self._queue.clear()
        self._released = STOP
        super().reset(context)

    def step(self, observation: Observation) -> VelocityCommand:
        self._queue.append((observation.time, super().step(observation)))
        due = observation.time - self.delay + SAME_TICK
        while self._queue and self._queue[0][0] <= due:
            self._released = self._queue.popleft()[1]
        return self._released


class _Lossy(Wrapper):
    """Each tick, with probability ``percent`` %, the base does not get the navigator's new
    command and does ``missed()`` instead."""

    family = ""

    def __init__(self, name: str, inner: Controller, percent: int) -> None:
        super().__init__(name, inner)
        self.chance = percent / 100
        self._rng = np.random.default_rng(0)  # reset() seeds it from the run
        self._delivered = STOP

    def reset(self, context: ControllerContext) -> None:
        self._rng = seeded(context, self.family)
        self._delivered = STOP
        super().reset(context)

    def missed(self) -> VelocityCommand:
        raise NotImplementedError

    def step(self, observation: Observation) -> VelocityCommand:
        lost = self._rng.random() < self.chance  # drawn every tick: the same ticks each run
        command = super().step(observation)
        self._delivered = self.missed() if lost else command
        return self._delivered


class Held(_Lossy):
    """Defect: each tick, with probability ``percent`` %, the base repeats the command it
    executed last instead of the navigator's new one (``STOP`` before the first).

    Imitates: ``cmd_vel`` over a lossy wireless link or a saturated DDS writer, with a base
    driver that keeps executing the last command it received until the next arrives.

    Expected catcher: REACTION_TIME and HUMAN_SLOW_ZONE (a slow-down that does not arrive),
    the collision requirements (a turn or a stop that comes late), SMOOTH_MOTION, goals
    overshot (MISSION_GOALS_REACHED, SETTLE).
    """

    family = "held"

    def missed(self) -> VelocityCommand:
        return self._delivered


class Dropped(_Lossy):
    """Defect: each tick, with probability ``percent`` %, the navigator's command is lost and
    the base stops for that tick (its command timeout is shorter than a control period).

    Imitates: the same lossy link with a cautious base driver that brakes whenever a command
    is overdue; the robot stutters.

    Expected catcher: TIME_TO_GOAL and EFFICIENT_PATH (it advances less per second), the
    command requirements (accelerations and chatter, where they exist), SMOOTH_MOTION.
    """

    family = "dropped"

    def missed(self) -> VelocityCommand:
        return STOP
