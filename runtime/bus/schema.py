"""The bus's wire schema, version 1: which key expression carries what, and how.

Any program that speaks Zenoh can join a REI run with what this module (and docs/bus.md)
says, whatever its language:

* every stamped message of ``rei.runtime.messages`` travels on ``rei/v1/<topic>`` (its
  ``TOPIC``, e.g. ``rei/v1/sensor/laser``) as one UTF-8 JSON object: ``message_to_json``'s
  form, with ``topic``, ``seq`` (0, 1, 2, ... per topic and run) and ``time`` (simulated
  seconds) first; numbers are finite (NaN and Infinity are refused);
* configuration is asked for with a query on ``rei/v1/config/<name>`` (``CONFIG_NAMES``)
  and answered with one JSON object;
* the run's sample stream travels on ``rei/v1/trace`` for monitors and viewers: trace.jsonl's
  own lines (header, samples, end), a keyframe of every object's row before every 10th
  sample and the sample count before the end (``rei.runtime.bus.distributed_run``).

The version is in the key, so a v2 can run beside v1 on one router. Payloads larger than
``MAX_PAYLOAD`` are refused by the sender and dropped by the receiver. This module must
never import zenoh or anything of the simulator: it is the contract, not a transport.
"""

from __future__ import annotations

import json
import math
from typing import Any

from rei.runtime.bus.errors import BusError
from rei.runtime.messages import (
    LOOP_MESSAGES,
    LoopMessage,
    MessageError,
    message_from_json,
    message_to_json,
)

WIRE_VERSION = 1
PREFIX = f"rei/v{WIRE_VERSION}"
"""Every key of this schema starts here."""

ALL = f"{PREFIX}/**"
CONFIG = f"{PREFIX}/config"
TRACE = f"{PREFIX}/trace"

CONFIG_NAMES = ("world", "robot", "trace")
"""What a query may ask for: the world manifest, the robot's context, the trace's header
line (the mission's facts are in it)."""

MAX_PAYLOAD = 4 << 20
"""Bytes one message may take on the wire (a laser scan of 10k beams is ~200 KB)."""


def topic_key(topic: str) -> str:
    """The key expression of a topic of ``rei.runtime.messages``."""
    if topic not in LOOP_MESSAGES:
        raise BusError(f"a topic expected to be one of {', '.join(sorted(LOOP_MESSAGES))}, "
                       f"found {topic!r}")
    return f"{PREFIX}/{topic}"


def config_key(name: str) -> str:
    if name not in CONFIG_NAMES:
        raise BusError(f"a configuration name expected to be one of "
                       f"{', '.join(CONFIG_NAMES)}, found {name!r}")
    return f"{CONFIG}/{name}"


def topic_of(key: str) -> str | None:
    """The topic a message key carries, None for a key outside the message topics."""
    if not key.startswith(PREFIX + "/"):
        return None
    topic = key[len(PREFIX) + 1:]
    return topic if topic in LOOP_MESSAGES else None


def _refuse_constant(token: str) -> Any:
    raise ValueError(f"{token} is not a number a message may hold")


def dumps(data: Any) -> bytes:
    """``data`` as the wire's compact JSON (finite numbers only; ValueError otherwise)."""
    return json.dumps(data, separators=(",", ":"), allow_nan=False).encode("utf-8")


def loads(payload: bytes) -> Any:
    """One payload's JSON; ``BusError`` saying why it is not one (size, UTF-8, syntax,
    NaN or Infinity)."""
    if len(payload) > MAX_PAYLOAD:
        raise BusError(f"a payload of at most {MAX_PAYLOAD} bytes expected, "
                       f"found {len(payload)}")
    try:
        return json.loads(payload.decode("utf-8"), parse_constant=_refuse_constant)
    except (UnicodeDecodeError, ValueError, RecursionError) as exc:
        raise BusError(f"a JSON payload expected: {exc}") from None


def encode_message(message: LoopMessage) -> bytes:
    """The payload of ``message`` on ``topic_key(message.TOPIC)``."""
    try:
        payload = dumps(message_to_json(message))
    except ValueError as exc:  # a non-finite number: never put on the wire
        raise BusError(f"{message.TOPIC}: cannot send seq {message.seq}: {exc}") from None
    if len(payload) > MAX_PAYLOAD:
        raise BusError(f"{message.TOPIC}: seq {message.seq} takes {len(payload)} bytes, "
                       f"more than the bus's {MAX_PAYLOAD}")
    return payload


def decode_message(key: str, payload: bytes) -> LoopMessage:
    """The message a sample on ``key`` carries; ``BusError`` naming the key and the field
    when it is not one, or when its topic is not the key's."""
    try:
        message = message_from_json(loads(payload))
    except (BusError, MessageError) as exc:
        raise BusError(f"{key}: {exc}") from None
    if topic_of(key) != message.TOPIC:
        raise BusError(f"{key}: a message of topic {topic_of(key)!r} expected, found "
                       f"{message.TOPIC!r}")
    if not math.isfinite(message.time):  # message_from_json refuses it; kept as the edge
        raise BusError(f"{key}: a finite time expected")
    return message
