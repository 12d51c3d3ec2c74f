"""The wire of the controller host: how requests and answers travel between the simulation
and the controller's process, and how an answer is decoded and checked.

Requests are length-prefixed pickles (the simulation trusts its own side); answers are one
JSON line each, never a pickle, decoded with NaN and Infinity refused, at most
``MAX_ANSWER`` bytes. This module must never import pybullet or call a controller.
"""

from __future__ import annotations

import json
import math
import signal
import struct
from typing import Any, BinaryIO, TypeVar

from rei.runtime.messages import NavState
from rei.runtime.robot.contract import (
    GoalFeedback,
    VelocityCommand,
)

MAX_ANSWER = 1 << 20
"""Bytes one answer of the host may take (a controller printing into the pipe is a fault)."""

Answer = TypeVar("Answer")

MAX_REASON = 2000
"""Characters of a fault's reason the host may give (an exception's message may be long)."""

ANSWERS = {"load": ("ok", "error"), "step": ("ok", "violation"),
            "feedback": ("ok", "violation")}
"""The keys an answer to each request may have besides "raised" (other requests: "ok": null)."""

FEEDBACK_AFTER = frozenset({"step", "send_goal"})
"""Requests after whose normal answer the host sends the controller's feedback as well."""

LENGTH = struct.Struct("!I")
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


def reason_text(value: Any) -> str:
    """A reason the host gave, as the run reports it (at most ``MAX_REASON`` characters)."""
    text = value if isinstance(value, str) else json.dumps(value)
    return text if len(text) <= MAX_REASON else text[:MAX_REASON - 3] + "..."


def violation_reason(what: str, reason: str, non_finite: bool) -> str:
    kind = "a non-finite" if non_finite else "an invalid"
    noun = "command" if what == "step" else "feedback"
    return f"controller {what}() sent {kind} {noun}: {reason}"


def read_exactly(stream: BinaryIO, size: int) -> bytes | None:
    data = b""
    while len(data) < size:
        chunk = stream.read(size - len(data))  # buffered: all of it unless the pipe closed
        if not chunk:
            return None
        data += chunk
    return data


def answer_line(answer: dict[str, Any]) -> bytes:
    return json.dumps(answer, allow_nan=False).encode("ascii")
