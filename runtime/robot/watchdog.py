"""Calling the robot under test safely: a hang, an exception or a non-finite command is a fault.

Every call goes to one daemon worker thread and the run waits for its answer at most
``timeout`` seconds of wall time. A call that does not return in time leaves its thread
behind (a daemon, so it never keeps the process alive) and raises ``ControllerFault``, as does
a call that raises. The run loop turns a fault into the outcome ``error`` with its reason.
This module must never import pybullet.
"""

from __future__ import annotations

import math
import queue
import threading
from collections.abc import Callable
from typing import Any

from rei.runtime.robot.protocol import (
    Controller,
    ControllerContext,
    GoalFeedback,
    NavGoal,
    Observation,
    VelocityCommand,
)


class ControllerFault(Exception):
    """The controller raised, hung or answered nonsense; ``str(fault)`` is the reason."""


class GuardedController:
    def __init__(self, controller: Controller, timeout: float | None) -> None:
        self.controller = controller
        self.timeout = timeout
        self._jobs: queue.SimpleQueue[tuple[Callable[..., Any], tuple[Any, ...]] | None] = \
            queue.SimpleQueue()
        self._answers: queue.SimpleQueue[tuple[bool, Any]] = queue.SimpleQueue()
        self._broken: str | None = None
        self._worker: threading.Thread | None = None
        if timeout is not None:
            self._worker = threading.Thread(target=self._serve, name="rei-controller",
                                            daemon=True)
            self._worker.start()

    def _serve(self) -> None:
        while True:
            job = self._jobs.get()
            if job is None:
                return
            fn, args = job
            try:
                self._answers.put((True, fn(*args)))
            except BaseException as exc:  # noqa: BLE001  (reported to the run, not lost)
                self._answers.put((False, exc))

    def _call(self, what: str, fn: Callable[..., Any], *args: Any) -> Any:
        if self._broken is not None:
            raise ControllerFault(self._broken)
        if self._worker is None:
            try:
                return fn(*args)
            except Exception as exc:  # noqa: BLE001
                self._broken = f"controller {what}() raised {type(exc).__name__}: {exc}"
                raise ControllerFault(self._broken) from None
        self._jobs.put((fn, args))
        try:
            ok, value = self._answers.get(timeout=self.timeout)
        except queue.Empty:
            self._broken = (f"controller {what}() did not return within the watchdog's "
                            f"{self.timeout:g} s")
            raise ControllerFault(self._broken) from None
        if not ok:
            if isinstance(value, KeyboardInterrupt):
                raise value
            self._broken = f"controller {what}() raised {type(value).__name__}: {value}"
            raise ControllerFault(self._broken)
        return value

    def close(self) -> None:
        if self._worker is not None and self._broken is None:
            self._jobs.put(None)
            self._worker.join(timeout=1.0)

    def reset(self, context: ControllerContext) -> None:
        self._call("reset", self.controller.reset, context)

    def send_goal(self, goal: NavGoal) -> None:
        self._call("send_goal", self.controller.send_goal, goal)

    def cancel_goal(self) -> None:
        self._call("cancel_goal", self.controller.cancel_goal)

    def feedback(self) -> GoalFeedback:
        fb = self._call("feedback", self.controller.feedback)
        if not isinstance(fb, GoalFeedback):
            self._broken = (f"controller feedback() returned {type(fb).__name__}, "
                            f"expected GoalFeedback")
            raise ControllerFault(self._broken)
        return fb

    def step(self, observation: Observation) -> VelocityCommand:
        cmd = self._call("step", self.controller.step, observation)
        if not isinstance(cmd, VelocityCommand):
            self._broken = (f"controller step() returned {type(cmd).__name__}, "
                            f"expected a VelocityCommand")
            raise ControllerFault(self._broken)
        if not (math.isfinite(cmd.linear) and math.isfinite(cmd.angular)):
            self._broken = (f"controller step() sent a non-finite command "
                            f"({cmd.linear}, {cmd.angular})")
            raise ControllerFault(self._broken)
        return cmd
