"""The controller host: the robot under test runs in its own process, behind messages.

A controller is a user's program, called every control tick. Inside the simulation's process
it could falsify its own test: patch REI's evaluator in memory, register an ``atexit`` hook
that rewrites summary.json, write a fake exit status into the supervisor's pipe. So
``HostedController`` runs it in a child process (``python -m rei.runtime.robot.host``,
started with ``rei.runtime.platform.processes.start_child``: its own process group, dead with the
thread that started it, no file descriptor but its two pipe ends and stderr, its working
folder a fresh temporary one) and talks to it only through messages:

* requests (simulation -> host) are pickles, length-prefixed: the simulation trusts its own
  side; a step's scan is sent once (the laser is slower than the control loop): the host
  keeps the controller's read-only copy for the next steps that carry the same scan;
* answers (host -> simulation) are one JSON line each, never a pickle (unpickling would let
  the controller run code in the simulation): plain numbers, strings and bools, decoded with
  NaN and Infinity refused, at most ``MAX_ANSWER`` bytes, then checked again by
  ``checked_command`` / ``checked_feedback`` as an in-process answer would be. The host's
  ``print`` goes to stderr, so a chatty controller cannot break the framing.

One round trip per control tick: the host answers ``step`` and ``send_goal`` (when they
return normally), then calls the controller's ``feedback()`` itself and sends its answer as a
second line (``FEEDBACK_AFTER``). ``feedback()`` on this side reads that line when it is
asked for, and keeps the feedback until the next call that can change the controller's state
(``reset``, ``send_goal``, ``cancel_goal``, ``step``); only when it holds none does it ask
the host. This relies on the ``Controller`` contract that ``feedback()`` is a pure function of
the controller's state. A feedback line nobody asked for before the next request is read and
dropped: what it says is no fault (no feedback was asked for), but a host that does not
finish it within the watchdog, dies or floods the pipe meanwhile is, named ``feedback()``.

Each answer is awaited at most ``timeout`` wall seconds (select on the pipe): a hang, even in
C holding the interpreter lock, stalls only the host, and the fault names the call. A host
that dies (``os._exit``, a signal, ``sys.exit`` from a thread) is a ``ControllerFault``
naming how it died. Every fault, and ``close``, kills the host's whole process group and
reaps it, so nothing the controller started writes anything after the run. The host's side
is ``serve``; it runs the same ``load_controller`` the in-process path runs. This module
must never import pybullet.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import pickle
import select
import signal
import struct
import subprocess
import sys
import tempfile
import time
import weakref
from collections.abc import Callable, Iterator
from dataclasses import replace
from typing import IO, Any, BinaryIO, TypeVar

from rei.runtime.errors import RunError
from rei.runtime.messages import LaserScan, NavState
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
    read_only_scan,
)
from rei.runtime.robot.teleop import SCRIPTS
from rei.runtime.robot.watchdog import ControllerFault, raised

MAX_ANSWER = 1 << 20
"""Bytes one answer of the host may take (a controller printing into the pipe is a fault)."""

Answer = TypeVar("Answer")

MAX_REASON = 2000
"""Characters of a fault's reason the host may give (an exception's message may be long)."""

_ANSWERS = {"load": ("ok", "error"), "step": ("ok", "violation"),
            "feedback": ("ok", "violation")}
"""The keys an answer to each request may have besides "raised" (other requests: "ok": null)."""

FEEDBACK_AFTER = frozenset({"step", "send_goal"})
"""Requests after whose normal answer the host sends the controller's feedback as well."""

_LENGTH = struct.Struct("!I")
"""The length prefix of a request."""


def describe_status(status: int) -> str:
    """How a process ended, from its exit status (negative: the signal that ended it)."""
    if status < 0:
        try:
            name = f" ({signal.Signals(-status).name})"
        except ValueError:
            name = ""
        return f"was killed by signal {-status}{name}"
    return f"exited with status {status}"


def _no_constant(token: str) -> Any:
    raise ValueError(f"{token} is not a number an answer may hold")


def decode_answer(line: bytes) -> dict[str, Any]:
    """One answer line as a JSON object; ValueError saying why it is not one."""
    try:
        value = json.loads(line.decode("utf-8"), parse_constant=_no_constant)
    except (UnicodeDecodeError, ValueError, RecursionError) as exc:
        raise ValueError(f"not a JSON answer ({exc})") from None
    if not isinstance(value, dict) or len(value) != 1:
        raise ValueError("expected a JSON object with one key")
    return value


def _number(value: Any) -> Any:
    """A JSON number as the controller sent it (its type is checked by the contract)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"expected a number, found {type(value).__name__}")
    return value


def command_of(answer: Any) -> VelocityCommand:
    """The command in a step() answer: a list of two JSON numbers."""
    if not isinstance(answer, list) or len(answer) != 2:
        raise ValueError("expected a list of two numbers")
    return VelocityCommand(_number(answer[0]), _number(answer[1]))


def feedback_of(answer: Any) -> GoalFeedback:
    """The feedback in a feedback() answer: state, goal, distance ("inf" allowed), message."""
    if not isinstance(answer, dict) or set(answer) != {"state", "goal", "distance", "message"}:
        raise ValueError("expected an object with state, goal, distance and message")
    try:
        state = NavState(answer["state"])
    except ValueError:
        raise ValueError(f"unknown goal state {str(answer['state'])[:40]!r}") from None
    distance = answer["distance"]
    if distance == "inf":
        distance = math.inf
    elif distance is not None:
        distance = _number(distance)
    goal, message = answer["goal"], answer["message"]
    if (goal is not None and not isinstance(goal, str)) or not isinstance(message, str):
        raise ValueError("expected the goal and the message as strings")
    return GoalFeedback(state, goal, distance, message)


class RemoteController:
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
            raise self._fault(_violated(what, _text(reason), non_finite is True))
        try:
            value = decode(answer.get("ok"))
            return check(value)
        except ContractViolation as problem:
            raise self._fault(_violated(what, str(problem), problem.non_finite)) from None
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
            raise self._fault(_text(answer["raised"]))
        key = next(iter(answer))  # decode_answer: exactly one
        allowed = _ANSWERS.get(op, ("ok",))
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
            [sys.executable, "-c", "from rei.runtime.robot.host import main; main()"],
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
            raise RunError(_text(answer["error"]))
        self._name = _text(answer["ok"])

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
                              f"{_text(answer['error'])}")
        self._name = _text(answer["ok"])

    @property
    def pid(self) -> int:
        """The host's process id (and its process group's)."""
        return self._process.pid

    def close(self) -> None:
        """Kill the host's process group and reap it (again: nothing happens)."""
        self._finalizer()

    def _request(self, op: str, args: tuple[Any, ...]) -> bytes:
        request = pickle.dumps((op, args), protocol=pickle.HIGHEST_PROTOCOL)
        return _LENGTH.pack(len(request)) + request

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


def _text(value: Any) -> str:
    """A reason the host gave, as the run reports it (at most ``MAX_REASON`` characters)."""
    text = value if isinstance(value, str) else json.dumps(value)
    return text if len(text) <= MAX_REASON else text[:MAX_REASON - 3] + "..."


def _violated(what: str, reason: str, non_finite: bool) -> str:
    kind = "a non-finite" if non_finite else "an invalid"
    noun = "command" if what == "step" else "feedback"
    return f"controller {what}() sent {kind} {noun}: {reason}"


def _stop(process: Child, home: tempfile.TemporaryDirectory[str]) -> None:
    stop_child(process)
    for stream in (process.stdin, process.stdout):
        if stream is not None:
            with contextlib.suppress(OSError):
                stream.close()
    with contextlib.suppress(OSError):
        home.cleanup()


# -- the host's side ------------------------------------------------------------------------

def _answer_of(what: str, controller: Any, args: tuple[Any, ...]) -> dict[str, Any]:
    """Call the controller; its answer as a JSON-ready object (never raises)."""
    try:
        value = getattr(controller, what)(*args)
    except BaseException as exc:  # noqa: BLE001  (KeyboardInterrupt and SystemExit too)
        return {"raised": raised(what, exc)}
    if what not in ("step", "feedback"):
        return {"ok": None}
    try:
        if what == "step":
            cmd = checked_command(value)
            return {"ok": [cmd.linear, cmd.angular]}
        fb = checked_feedback(value)
    except ContractViolation as problem:
        return {"violation": [str(problem), problem.non_finite]}
    except Exception as exc:  # noqa: BLE001  (a user's subclass whose fields raise)
        return {"raised": raised(what, exc) + " while its answer was read"}
    distance = fb.distance_remaining
    return {"ok": {"state": fb.state.value, "goal": fb.goal,
                   "distance": "inf" if distance == math.inf else distance,
                   "message": fb.message}}


def _read_exactly(stream: BinaryIO, size: int) -> bytes | None:
    data = b""
    while len(data) < size:
        chunk = stream.read(size - len(data))  # buffered: all of it unless the pipe closed
        if not chunk:
            return None
        data += chunk
    return data


class HostSide:
    """The host's side of the robot contract, whatever carries it: one request in, its
    answer lines out (JSON, never a pickle), the controller called in this thread. The pipe
    host (``serve``) and the bus's robot (`rei robot`) both answer with it, so a controller
    answers the same bytes whichever way it is reached. ``load`` makes the controller for
    a load request's arguments (RunError: the answer says why)."""

    def __init__(self, load: Callable[..., Any]) -> None:
        self._load = load
        self.controller: Any = None
        self._scan: LaserScan | None = None  # the controller's read-only copy of the last scan

    def answers(self, op: str, args: tuple[Any, ...]) -> Iterator[bytes]:
        """The answer lines (each without its newline) to the request ``op(*args)``, each
        as soon as it is known (the feedback after a step's command is computed after the
        command is sent: a hang there is the feedback's, not the step's)."""
        if op == "load":
            try:
                self.controller = self._load(*args)
                self._scan = None
                answer: dict[str, Any] = {"ok": str(getattr(self.controller, "name",
                                                           args[0] if args else "?"))}
            except RunError as exc:
                answer = {"error": str(exc)}
            yield _line(answer)
            return
        if op == "step":  # (observation, whether its scan is the last step's)
            observation, same = args
            if not same:
                self._scan = read_only_scan(observation.scan)
            args = (replace(observation, scan=self._scan),)
        answer = _answer_of(op, self.controller, args)
        yield _line(answer)
        if op in FEEDBACK_AFTER and "ok" in answer:  # what the next tick asks first
            yield _line(_answer_of("feedback", self.controller, ()))


def _line(answer: dict[str, Any]) -> bytes:
    return json.dumps(answer, allow_nan=False).encode("ascii")


def serve(requests: BinaryIO, answers: BinaryIO) -> None:
    """The host's loop: load the controller, then answer each request until the end of
    the requests (the simulation closed the pipe or was killed)."""
    from rei.runtime.robot.selection import load_controller  # noqa: PLC0415

    host = HostSide(load_controller)
    while True:
        head = _read_exactly(requests, _LENGTH.size)
        if head is None:
            return
        body = _read_exactly(requests, _LENGTH.unpack(head)[0])
        if body is None:
            return
        op, args = pickle.loads(body)  # noqa: S301  (written by the simulation: trusted)
        for line in host.answers(op, args):
            answers.write(line + b"\n")
            answers.flush()


def main() -> None:
    # The pipes move to descriptors of their own; 0 reads nothing and 1 is stderr, so what
    # the controller prints cannot be taken for an answer.
    # Buffered: a request's length prefix and body usually arrive in one read of the pipe.
    requests = os.fdopen(os.dup(0), "rb")
    answers = os.fdopen(os.dup(1), "wb")
    devnull = os.open(os.devnull, os.O_RDONLY)
    os.dup2(devnull, 0)
    os.close(devnull)
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    serve(requests, answers)


if __name__ == "__main__":
    main()
