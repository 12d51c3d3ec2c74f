"""Calling the robot under test safely: a hang, an exception or a malformed answer is a fault.

A ``HostedController`` (what ``make_controller`` gives, and so what `rei run` and campaigns
run) lives in its own process (``rei.runtime.robot.host``): the guard hands it the timeout
and passes its faults on; a hang, even in C, or the death of that process is then a fault
with its precise reason, and the controller cannot touch the simulation's memory. Any other
controller object (a library caller's, ``check_controller``'s) runs in this process: every
call goes to one daemon worker thread and the run waits for its answer at most
``timeout`` seconds of wall time. A call that does not return in time leaves its thread
behind (a daemon, so it never keeps the process alive) and raises ``ControllerFault``, as does
a call that raises (``sys.exit()`` included: in the worker it is an exception like any other)
and an answer that breaks the contract (``checked_command``, ``checked_feedback``: a string, a
complex number, an array, an int beyond float range, a non-finite number, a feedback of the
wrong types). The fault is raised where the answer is received, so its reason names the call.
A KeyboardInterrupt raised in the worker is the controller's own (the user's Ctrl-C reaches
the main thread), so it is a fault too. The run loop turns a fault into the outcome ``error``
with its reason.

The feedback is kept from one ``feedback()`` to the next call that can change the
controller's state (``reset``, ``send_goal``, ``cancel_goal``, ``step``): the mission asks for
it twice a tick, and the ``Controller`` contract makes it a pure function of that state. The
worker thread also computes it right after a ``step`` or ``send_goal`` that returned, so the
next tick's ``feedback()`` finds it waiting: one hand-off per control tick. Its faults are
raised when it is asked for, as if it were computed then; one nobody asks for before the next
call is dropped, unless it has not returned within the watchdog by then (a fault of
``feedback()``: the worker is stuck in it).

What this in-process thread cannot catch is a call that never gives the interpreter back (a
loop in C holding the GIL) or that ends the process (``os._exit``, a signal): the main thread
is then stopped too, so those are caught one level up, by the process that supervises the
run (``rei.runtime.runs.supervisor``). This module must never import pybullet.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable
from typing import Any, TypeVar

from rei.runtime.robot.contract import (
    ContractViolation,
    Controller,
    ControllerContext,
    GoalFeedback,
    NavGoal,
    Observation,
    VelocityCommand,
    checked_command,
    checked_feedback,
)

T = TypeVar("T")


def raised(what: str, exc: BaseException) -> str:
    """The reason for a call that raised; never raises itself (a user's __str__ may)."""
    try:
        text = str(exc)
    except Exception:  # noqa: BLE001
        text = "<unprintable>"
    if isinstance(exc, SystemExit):
        return f"controller {what}() tried to end the process (SystemExit: {text})"
    return f"controller {what}() raised {type(exc).__name__}: {text}"


_Job = tuple[Callable[..., Any], tuple[Any, ...], Callable[[], Any] | None]
"""What the worker thread calls: a controller method, its arguments, and what to call after."""


class ControllerFault(Exception):
    """The controller raised, hung or answered nonsense; ``str(fault)`` is the reason."""


class SelfTimedController:
    """A controller that waits for its own answers, at most ``timeout`` wall seconds each,
    and reports every failure as a ``ControllerFault`` (the controller host's caller,
    rei.runtime.robot.host.caller.RemoteController): the watchdog hands it its timeout and
    calls it directly, with no worker thread of its own."""

    timeout: float | None

    def close(self) -> None:
        """Stop the controller for good."""


class GuardedController:
    def __init__(self, controller: Controller, timeout: float | None) -> None:
        self.controller = controller
        self.timeout = timeout
        self._hosted: SelfTimedController | None = None
        if isinstance(controller, SelfTimedController):
            self._hosted = controller
            controller.timeout = timeout  # it waits for its own answers
        self._jobs: queue.SimpleQueue[_Job | None] = queue.SimpleQueue()
        self._answers: queue.SimpleQueue[tuple[bool, Any]] = queue.SimpleQueue()
        self._broken: str | None = None
        self._feedback: GoalFeedback | None = None
        """The feedback as of the controller's last state-changing call (None: unknown)."""
        self._pending = False
        """Whether the worker answers a feedback() of its own before the next call's."""
        self._worker: threading.Thread | None = None
        if timeout is not None and self._hosted is None:
            self._worker = threading.Thread(target=self._serve, name="rei-controller",
                                            daemon=True)
            self._worker.start()

    def _serve(self) -> None:
        while True:
            job = self._jobs.get()
            if job is None:
                return
            fn, args, then = job
            try:
                self._answers.put((True, fn(*args)))
            except BaseException as exc:  # noqa: BLE001  (reported to the run, not lost)
                self._answers.put((False, exc))
                continue
            if then is not None:  # the feedback the next tick asks for first
                try:
                    self._answers.put((True, then()))
                except BaseException as exc:  # noqa: BLE001  (reported when asked for)
                    self._answers.put((False, exc))

    def _late(self, what: str) -> ControllerFault:
        self._broken = (f"controller {what}() did not return within the watchdog's "
                        f"{self.timeout:g} s")
        return ControllerFault(self._broken)

    def _call(self, what: str, fn: Callable[..., Any], *args: Any,
              then: Callable[[], Any] | None = None) -> Any:
        """Call ``fn`` (the controller's ``what``) under the watchdog; ``then``: what the
        worker calls after it returned, its answer read by ``feedback()``."""
        if self._broken is not None:
            raise ControllerFault(self._broken)
        if what != "feedback":  # the controller's state may change: its feedback with it
            self._feedback = None
        if self._hosted is not None:  # its faults are ControllerFaults already
            return fn(*args)
        if self._worker is None:
            try:
                return fn(*args)
            except KeyboardInterrupt:
                raise
            except BaseException as exc:  # noqa: BLE001  (SystemExit too: a fault, not an exit)
                self._broken = raised(what, exc)
                raise ControllerFault(self._broken) from None
        if self._pending:  # a feedback nobody asked for: dropped, unless it hangs
            self._pending = False
            try:
                self._answers.get(timeout=self.timeout)
            except queue.Empty:
                raise self._late("feedback") from None
        self._jobs.put((fn, args, then))
        try:
            ok, value = self._answers.get(timeout=self.timeout)
        except queue.Empty:
            raise self._late(what) from None
        if not ok:  # a KeyboardInterrupt here is the controller's own: a fault too
            self._broken = raised(what, value)
            raise ControllerFault(self._broken)
        self._pending = then is not None
        return value

    def _violated(self, what: str, problem: ContractViolation) -> ControllerFault:
        kind = "a non-finite" if problem.non_finite else "an invalid"
        noun = "command" if what == "step" else "feedback"
        self._broken = f"controller {what}() sent {kind} {noun}: {problem}"
        return ControllerFault(self._broken)

    def close(self) -> None:
        """End the controller (once): a hosted one's process group is killed and reaped."""
        if self._hosted is not None:
            self._hosted.close()
        if self._worker is not None and self._broken is None and self._worker.is_alive():
            self._jobs.put(None)
            self._worker.join(timeout=1.0)

    def reset(self, context: ControllerContext) -> None:
        self._call("reset", self.controller.reset, context)

    def send_goal(self, goal: NavGoal) -> None:
        self._call("send_goal", self.controller.send_goal, goal, then=self.controller.feedback)

    def cancel_goal(self) -> None:
        self._call("cancel_goal", self.controller.cancel_goal)

    def feedback(self) -> GoalFeedback:
        """The controller's feedback, kept until its next state-changing call."""
        if self._broken is not None:
            raise ControllerFault(self._broken)
        if self._feedback is None:
            answer = self._fresh_feedback()
            # a hosted controller's answers are checked as they arrive
            self._feedback = answer if self._hosted is not None else \
                self._checked_feedback(answer)
        return self._feedback

    def _fresh_feedback(self) -> Any:
        """What the controller's feedback() answers now (the worker's, if it computed it)."""
        if not self._pending:
            return self._call("feedback", self.controller.feedback)
        self._pending = False
        try:
            ok, value = self._answers.get(timeout=self.timeout)
        except queue.Empty:
            raise self._late("feedback") from None
        if not ok:
            self._broken = raised("feedback", value)
            raise ControllerFault(self._broken)
        return value

    def _checked_feedback(self, answer: Any) -> GoalFeedback:
        return self._checked("feedback", checked_feedback, answer)

    def _checked(self, what: str, check: Callable[[Any], T], answer: Any) -> T:
        """``check(answer)``; a ControllerFault naming ``what`` when the answer breaks the
        contract or raises while it is read."""
        try:
            return check(answer)
        except ContractViolation as problem:
            raise self._violated(what, problem) from None
        except Exception as exc:  # noqa: BLE001  (a user's subclass whose fields raise)
            self._broken = raised(what, exc) + " while its answer was read"
            raise ControllerFault(self._broken) from None

    def step(self, observation: Observation) -> VelocityCommand:
        answer = self._call("step", self.controller.step, observation,
                            then=self.controller.feedback)
        if self._hosted is not None:  # checked as it arrived
            return answer  # type: ignore[no-any-return]
        return self._checked("step", checked_command, answer)
