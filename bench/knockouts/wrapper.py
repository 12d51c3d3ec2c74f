"""What every knock-out shares: a controller that hands each call on to the navigator it wraps,
and the choice of that navigator (``REI_KNOCKOUT_BASE``).

A knock-out knows its base only through the public controller protocol (contract.py): what it
is told (context, goal), what it sees (the observation) and what it answers (commands,
feedback). It must never reach into the base's attributes, so no refactoring of the reference
navigator can make a knock-out equivalent to it. Its commands are the base's or ``STOP``, never
made up; its feedback is the base's or a goal it ended itself, and never changes anything.
"""

from __future__ import annotations

import os
import zlib

import numpy as np

from rei.runtime.errors import RunError
from rei.runtime.messages import NavState
from rei.runtime.robot.contract import (
    STOP,
    Controller,
    ControllerContext,
    GoalFeedback,
    NavGoal,
    Observation,
    VelocityCommand,
)
from rei.runtime.robot.loading import load_controller

BASE_VARIABLE = "REI_KNOCKOUT_BASE"
"""The environment variable naming the navigator every knock-out wraps, as ``--controller``
takes it (``reference`` when unset or empty). ``rei run --controller bench.knockouts:NAME``
calls the knock-out with no arguments, so the choice travels in the environment, which every
run's process inherits."""
DEFAULT_BASE = "reference"


def base_spec() -> str:
    """The ``--controller`` spec of the navigator knock-outs wrap now."""
    return os.environ.get(BASE_VARIABLE, "").strip() or DEFAULT_BASE


def base_controller() -> Controller:
    """A fresh navigator of ``base_spec()`` (RunError naming the choices when unknown)."""
    spec = base_spec()
    if spec.partition(":")[0] == __name__.rpartition(".")[0]:
        # its own base would be the same variable again: a knock-out wrapping itself forever
        raise RunError(f"{BASE_VARIABLE}: expected a navigator, found the knock-out '{spec}' "
                       f"(wrap one knock-out in another in Python: make(NAME, inner))")
    return load_controller(spec)


def seeded(context: ControllerContext, family: str) -> np.random.Generator:
    """The random numbers of one run of a knock-out: the run's seed (so two runs of the same
    mission and seed are bit for bit the same) and the family (so two families on one run do
    not draw the same numbers)."""
    return np.random.default_rng([context.seed % 2**63, zlib.crc32(family.encode())])


class Wrapper:
    """A controller that hands every call on to ``inner``; a knock-out overrides the calls its
    defect changes.

    A knock-out that ends a goal itself (``end_goal``: a goal checker that succeeds early, a
    navigator that aborts instead of recovering) cancels it in ``inner`` and answers the ended
    goal's feedback until the next goal; the inner navigator is still stepped (its clock and
    odometry history stay whole) but the base gets ``STOP``.
    """

    def __init__(self, name: str, inner: Controller) -> None:
        self.name = name if inner.name == DEFAULT_BASE else f"{name}({inner.name})"
        self.inner = inner
        self._goal: NavGoal | None = None
        self._ended: GoalFeedback | None = None

    def reset(self, context: ControllerContext) -> None:
        self._goal, self._ended = None, None
        self.inner.reset(context)

    def send_goal(self, goal: NavGoal) -> None:
        self._goal, self._ended = goal, None
        self.inner.send_goal(goal)

    def cancel_goal(self) -> None:
        if self._ended is None:  # a goal the wrapper ended is over: nothing to cancel
            self.inner.cancel_goal()

    def feedback(self) -> GoalFeedback:
        return self._ended if self._ended is not None else self.inner.feedback()

    def step(self, observation: Observation) -> VelocityCommand:
        command = self.inner.step(observation)
        return command if self._ended is None else STOP

    def end_goal(self, state: NavState, message: str = "",
                 distance: float | None = None) -> None:
        """End the running goal as ``state`` on the wrapper's own authority."""
        self.inner.cancel_goal()
        name = self._goal.name if self._goal is not None else None
        self._ended = GoalFeedback(state, name, distance, message)
