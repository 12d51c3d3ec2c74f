"""The answering side of the controller host: ``HostSide`` (one request in, its answer
lines out, the controller called in this thread) and ``serve``/``main``, the host process's
loop. The pipe host and the bus's robot (`rei robot`) both answer with ``HostSide``. This
module must never import pybullet.
"""

from __future__ import annotations

import math
import os
import pickle
import sys
from collections.abc import Callable, Iterator
from dataclasses import replace
from typing import Any, BinaryIO

from rei.runtime.errors import RunError
from rei.runtime.messages import LaserScan
from rei.runtime.robot.contract import (
    ContractViolation,
    checked_command,
    checked_feedback,
    read_only_scan,
)
from rei.runtime.robot.host.wire import (
    FEEDBACK_AFTER,
    LENGTH,
    answer_line,
    read_exactly,
)
from rei.runtime.robot.watchdog import raised


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
            yield answer_line(answer)
            return
        if op == "step":  # (observation, whether its scan is the last step's)
            observation, same = args
            if not same:
                self._scan = read_only_scan(observation.scan)
            args = (replace(observation, scan=self._scan),)
        answer = _answer_of(op, self.controller, args)
        yield answer_line(answer)
        if op in FEEDBACK_AFTER and "ok" in answer:  # what the next tick asks first
            yield answer_line(_answer_of("feedback", self.controller, ()))


def serve(requests: BinaryIO, answers: BinaryIO) -> None:
    """The host's loop: load the controller, then answer each request until the end of
    the requests (the simulation closed the pipe or was killed)."""
    from rei.runtime.robot.loading import load_controller  # noqa: PLC0415

    host = HostSide(load_controller)
    while True:
        head = read_exactly(requests, LENGTH.size)
        if head is None:
            return
        body = read_exactly(requests, LENGTH.unpack(head)[0])
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
