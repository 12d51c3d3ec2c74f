"""The caller's side of the controller host: ``RemoteController`` (the simulation's side of
the robot contract, whatever carries it) and ``HostedController`` (over the pipes of a child
process). This module must never import pybullet, nor unpickle what a controller sent.
"""

from __future__ import annotations

import contextlib
import math
import os
import pickle
import select
import subprocess
import sys
import tempfile
import time
import weakref
from collections.abc import Callable
from dataclasses import replace
from typing import IO, Any

from rei.runtime.errors import RunError
from rei.runtime.messages import LaserScan
from rei.runtime.platform.processes import Child, start_child, stop_child
from rei.runtime.robot.contract import (
    ContractViolation,
    ControllerContext,
    GoalFeedback,
    NavGoal,
    Observation,
    VelocityCommand,
    checked_command,
    checked_feedback,
)
from rei.runtime.robot.host.answerer import main
from rei.runtime.robot.host.wire import (
    ANSWERS,
    FEEDBACK_AFTER,
    LENGTH,
    MAX_ANSWER,
    Answer,
    command_of,
    decode_answer,
    describe_status,
    feedback_of,
    reason_text,
    violation_reason,
)
from rei.runtime.robot.teleop import SCRIPTS
from rei.runtime.robot.watchdog import ControllerFault, SelfTimedController


class RemoteController(SelfTimedController):
    """The simulation's side of the robot contract, whatever carries it: the ``Controller``
    protocol, plus ``close``.

    One request per call, one JSON answer line back (two after ``step`` and ``send_goal``:
    the feedback follows, ``FEEDBACK_AFTER``), every answer checked by the same rules
    (``decode_answer``, the keys each request may answer, ``checked_command``,
    ``checked_feedback``). A subclass carries the bytes: ``HostedController`` over the pipes
    of a child process, ``rei.runtime.bus.remote_robot.BusController`` over the bus. Calls wait at
    most ``timeout`` wall seconds (None: as long as it takes); every failure is a
    ``ControllerFault`` with the reason a run reports, and stops the controller for good.
    """

    timeout: float | None
    spec: str
    _broken: str | None
    _feedback: GoalFeedback | None
    _pending: bool
    _scan: LaserScan | None

    def _loaded(self) -> None:
        """Await whatever the first call must wait for (nothing here)."""

    def close(self) -> None:
        raise NotImplementedError

    def _request(self, op: str, args: tuple[Any, ...]) -> bytes:
        raise NotImplementedError

    def _send(self, data: bytes, deadline: float | None) -> bool:
        """Send a request; False when it is not taken before the deadline."""
        raise NotImplementedError

    def _receive(self, what: str, deadline: float | None) -> bytes:
        """The next answer line (without its newline), or a ControllerFault."""
        raise NotImplementedError

    # -- the protocol -----------------------------------------------------------------------

    def reset(self, context: ControllerContext) -> None:
        self._call("reset", "reset", context)

    def send_goal(self, goal: NavGoal) -> None:
        self._call("send_goal", "send_goal", goal)

    def cancel_goal(self) -> None:
        self._call("cancel_goal", "cancel_goal")

    def feedback(self) -> GoalFeedback:
        """The feedback the host sent after the last step or goal, else asked for; kept
        until the next call that can change the controller's state."""
        if self._broken is not None:
            raise ControllerFault(self._broken)
        if self._feedback is None:
            if self._pending:
                self._pending = False
                answer = self._answer("feedback", "feedback", self._deadline())
            else:
                answer = self._call("feedback", "feedback")
            self._feedback = self._checked("feedback", feedback_of, checked_feedback, answer)
        return self._feedback

    def step(self, observation: Observation) -> VelocityCommand:
        scan = observation.scan
        if scan is not None and scan is self._scan:  # the host has it: not sent again
            request: tuple[Any, ...] = (replace(observation, scan=None), True)
        else:
            request, self._scan = (observation, False), scan
        return self._checked("step", command_of, checked_command,
                             self._call("step", "step", *request))

    # -- messages ---------------------------------------------------------------------------

    def _checked(self, what: str, decode: Callable[[Any], Any],
                 check: Callable[[Any], Answer], answer: dict[str, Any]) -> Answer:
        """The value of an answer to ``what`` (step or feedback), decoded and checked."""
        if "violation" in answer:
            reason = answer["violation"]
            non_finite = False
            if isinstance(reason, list) and len(reason) == 2:
                reason, non_finite = reason
            raise self._fault(violation_reason(what, reason_text(reason), non_finite is True))
        try:
            value = decode(answer.get("ok"))
            return check(value)
        except ContractViolation as problem:
            raise self._fault(violation_reason(what, str(problem), problem.non_finite)) from None
        except ValueError as exc:
            raise self._fault(f"controller {what}() answered nonsense: {exc}") from None

    def _fault(self, reason: str) -> ControllerFault:
        self._broken = reason
        self.close()
        return ControllerFault(reason)

    def _deadline(self) -> float | None:
        return None if self.timeout is None else time.monotonic() + self.timeout

    def _call(self, what: str, op: str, *args: Any) -> dict[str, Any]:
        if self._broken is not None:
            raise ControllerFault(self._broken)
        self._loaded()
        if op != "feedback":  # the controller's state may change: its feedback with it
            self._feedback = None
        try:
            if self._pending:  # a feedback nobody asked for: dropped, unless it hangs
                self._pending = False
                self._receive("feedback", self._deadline())
            deadline = self._deadline()
            if not self._send(self._request(op, args), deadline):
                raise self._fault(self._late(what))
        except KeyboardInterrupt:  # the user's Ctrl-C, in this process: its answer is lost
            self._fault(f"controller {what}() was interrupted by the user")
            raise
        answer = self._answer(what, op, deadline)
        self._pending = op in FEEDBACK_AFTER and "ok" in answer
        return answer

    def _answer(self, what: str, op: str, deadline: float | None) -> dict[str, Any]:
        """The answer to the request sent last, checked for its framing and keys."""
        try:
            line = self._receive(what, deadline)
        except KeyboardInterrupt:  # the user's Ctrl-C, in this process: its answer is lost
            self._fault(f"controller {what}() was interrupted by the user")
            raise
        try:
            answer = decode_answer(line)
        except ValueError as exc:
            raise self._fault(f"controller {what}() answered nonsense: {exc}") from None
        if "raised" in answer:
            raise self._fault(reason_text(answer["raised"]))
        key = next(iter(answer))  # decode_answer: exactly one
        allowed = ANSWERS.get(op, ("ok",))
        if key not in allowed:
            raise self._fault(f"controller {what}() answered nonsense: expected one of "
                              f"{', '.join(allowed)}, found {key[:40]!r}")
        if allowed == ("ok",) and answer["ok"] is not None:
            raise self._fault(f"controller {what}() answered nonsense: expected no value")
        return answer

    def _late(self, what: str) -> str:
        return f"controller {what}() did not return within the watchdog's {self.timeout:g} s"

    def _remaining(self, deadline: float | None) -> float | None:
        return None if deadline is None else max(0.0, deadline - time.monotonic())


class HostedController(RemoteController):
    """A controller running in its own process; the ``Controller`` protocol, plus ``close``.

    Calls wait at most ``timeout`` wall seconds (None: as long as it takes); every failure
    is a ``ControllerFault`` with the reason a run reports, and stops the host for good.
    """

    def __init__(self, spec: str, folder: str | None = None,
                 timeout: float | None = None) -> None:
        """Start the host and load ``spec`` in it (user modules from ``folder``, default the
        current one); RunError when the spec does not name a controller, as in-process."""
        self.timeout = timeout
        self.spec = spec
        self._broken: str | None = None
        self._buffer = b""
        self._feedback: GoalFeedback | None = None
        """The controller's feedback as of its last state-changing call (None: unknown)."""
        self._pending = False
        """Whether the host sends a feedback line before the next request's answer."""
        self._scan: LaserScan | None = None
        """The scan of the last step sent: the host keeps its copy for the next steps."""
        self._home = tempfile.TemporaryDirectory(prefix="rei-controller-")
        self._process: Child = start_child(
            [sys.executable, "-c", "from rei.runtime.robot.host.answerer import main; main()"],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, cwd=self._home.name, warm=main)
        assert self._process.stdin is not None and self._process.stdout is not None
        self._requests: IO[bytes] = self._process.stdin
        self._answers: IO[bytes] = self._process.stdout
        os.set_blocking(self._requests.fileno(), False)
        os.set_blocking(self._answers.fileno(), False)  # read before waiting (``_receive``)
        self._finalizer = weakref.finalize(self, _stop, self._process, self._home)
        self._name: str | None = None
        self.load_wait = 0.0
        """Wall seconds the first call waited for a built-in controller's process to be
        ready (its start-up not hidden behind the caller's own work)."""
        self._loading: float | None = None
        """Wall seconds the load's answer is still awaited for (NaN: as long as it takes)."""
        home = os.getcwd() if folder is None else folder
        if built_in(spec):
            # Nothing of the user's to import, so nothing to report before the run: the
            # host starts (a second interpreter's imports) while this process builds the
            # world, and its answer is awaited with the first call.
            self._loading = math.nan if timeout is None else timeout
            if not self._send(self._request("load", (spec, home)),
                              None if timeout is None else time.monotonic() + timeout):
                self._loading = None
                self.close()
                raise RunError(f"--controller: '{spec}' could not be started: "
                               f"{self._late('load')}")
            return
        try:
            answer = self._call("load", "load", spec, home)
        except ControllerFault as fault:
            self.close()
            raise RunError(f"--controller: '{spec}' could not be started: {fault}") from None
        if "error" in answer:
            self.close()
            raise RunError(reason_text(answer["error"]))
        self._name = reason_text(answer["ok"])

    @property
    def name(self) -> str:
        """The controller's name, as it gives it."""
        self._loaded()
        return self.spec if self._name is None else self._name

    @name.setter
    def name(self, value: str) -> None:
        self._loaded()
        self._name = value

    def _loaded(self) -> None:
        """Await the answer of a load sent without waiting; a ControllerFault if it failed."""
        if self._loading is None:
            return
        wait, self._loading = self._loading, None
        began = time.monotonic()
        deadline = None if math.isnan(wait) else began + wait
        try:
            answer = self._answer("load", "load", deadline)
        finally:
            self.load_wait = time.monotonic() - began
        if "error" in answer:
            raise self._fault(f"the controller's process could not load '{self.spec}': "
                              f"{reason_text(answer['error'])}")
        self._name = reason_text(answer["ok"])

    @property
    def pid(self) -> int:
        """The host's process id (and its process group's)."""
        return self._process.pid

    def close(self) -> None:
        """Kill the host's process group and reap it (again: nothing happens)."""
        self._finalizer()

    def _request(self, op: str, args: tuple[Any, ...]) -> bytes:
        request = pickle.dumps((op, args), protocol=pickle.HIGHEST_PROTOCOL)
        return LENGTH.pack(len(request)) + request

    def _send(self, data: bytes, deadline: float | None) -> bool:
        """Write the request; False when the host does not take it before the deadline."""
        fd = self._requests.fileno()
        view = memoryview(data)
        ready: list[int] = [fd]  # a request fits in an empty pipe: try before waiting
        while view:
            if not ready:
                _, ready, _ = select.select([], [fd], [], self._remaining(deadline))
                if not ready:
                    return False
            try:
                view = view[os.write(fd, view):]
            except BlockingIOError:
                ready = []
                continue
            except BrokenPipeError:
                return True  # the host is gone: the answer's end of file says how
        return True

    def _receive(self, what: str, deadline: float | None) -> bytes:
        fd = self._answers.fileno()
        while b"\n" not in self._buffer:
            if len(self._buffer) > MAX_ANSWER:
                raise self._fault(f"controller {what}() sent an answer longer than "
                                  f"{MAX_ANSWER} bytes")
            # Read first, wait only when nothing is there: the feedback line after a step's
            # answer is usually in the pipe already, and then costs one system call, not two.
            try:
                chunk = os.read(fd, 65536)
            except BlockingIOError:
                ready, _, _ = select.select([fd], [], [], self._remaining(deadline))
                if not ready:
                    raise self._fault(self._late(what)) from None
                chunk = os.read(fd, 65536)
            if not chunk:
                raise self._fault(self._ended(what, deadline))
            self._buffer += chunk
        line, _, self._buffer = self._buffer.partition(b"\n")
        if len(line) > MAX_ANSWER:
            raise self._fault(f"controller {what}() sent an answer longer than "
                              f"{MAX_ANSWER} bytes")
        return line

    def _ended(self, what: str, deadline: float | None) -> str:
        """The reason for a host whose answer pipe closed: how its process ended."""
        try:
            status = self._process.wait(timeout=self._remaining(deadline))
        except subprocess.TimeoutExpired:
            return f"controller {what}() closed its process's answer pipe"
        return f"the controller's process {describe_status(status)} during {what}()"


def built_in(spec: str) -> bool:
    """Whether ``spec`` names one of REI's own controllers (no user module to import)."""
    if spec.startswith("teleop:"):
        return spec.split(":", 1)[1] in SCRIPTS
    return spec in ("reference", "teleop")


def _stop(process: Child, home: tempfile.TemporaryDirectory[str]) -> None:
    stop_child(process)
    for stream in (process.stdin, process.stdout):
        if stream is not None:
            with contextlib.suppress(OSError):
                stream.close()
    with contextlib.suppress(OSError):
        home.cleanup()
