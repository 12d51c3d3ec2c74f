"""The robot contract over the bus: ``BusController`` (the simulation's side) and
``serve_robot`` (`rei robot`'s side).

The contract is the pipe host's (``rei.runtime.robot.host``): the same requests (load,
reset, send_goal, cancel_goal, feedback, step, and close at the end of a run), the same
answer lines, checked by the same rules (``RemoteController``), answered by the same code
(``HostSide``). Only the carrier differs: each request is a query on
``rei/v1/robot/call/<op>`` with a JSON payload ``{"args": [...]}`` (dataclasses as objects of
their fields, tuples and arrays as lists; never a pickle: the robot may be another program
on another machine), and the answer is the reply's payload, the answer lines joined by
newlines. The mission executor's calls (send_goal, cancel_goal) go through the mission
role's session, the others through the simulation's: the router lets only the mission send
goals. Lock-step: the simulation waits for each answer at most the watchdog; a robot that
does not answer (gone, hung, cut off) is a ``ControllerFault`` naming the call and the bus.
This module must never import pybullet.
"""

from __future__ import annotations

import collections
import dataclasses
import functools
import math
import threading
import time
import types
from collections.abc import Callable
from typing import Any, Union, cast, get_args, get_origin, get_type_hints

import numpy as np

from rei.runtime.bus.access import ROBOT_CALL
from rei.runtime.bus.client import BusSession
from rei.runtime.bus.errors import BusError, NoAnswer
from rei.runtime.bus.schema import dumps, loads
from rei.runtime.errors import RunError
from rei.runtime.messages import LaserScan
from rei.runtime.robot.contract import ControllerContext, NavGoal, Observation
from rei.runtime.robot.host import HostSide, RemoteController

OPS: dict[str, tuple[Any, ...]] = {
    "load": (), "reset": (ControllerContext,), "send_goal": (NavGoal,), "cancel_goal": (),
    "feedback": (), "step": (Observation, bool), "close": (),
}
"""Each request and the types of its arguments."""

MISSION_OPS = frozenset({"send_goal", "cancel_goal"})
"""The requests only the mission role may send."""

FOREVER = 365 * 24 * 3600.0
"""Wall seconds a call waits without a watchdog."""


def to_json(value: Any) -> Any:
    """A request's argument as JSON-ready data (floats kept exact: JSON writes their repr)."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: to_json(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, tuple | list):
        return [to_json(v) for v in value]
    return value


def from_json(hint: Any, value: Any, where: str) -> Any:  # noqa: PLR0911  (one per type)
    """``value`` as ``hint`` (the inverse of ``to_json``); ValueError naming ``where``."""
    if hint is bool:
        if not isinstance(value, bool):
            raise ValueError(f"{where}: expected true or false, found {value!r}")
        return value
    if hint is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ValueError(f"{where}: expected an integer, found {value!r}")
        return value
    if hint is float:
        if isinstance(value, bool) or not isinstance(value, int | float) \
                or not math.isfinite(value):
            raise ValueError(f"{where}: expected a finite number, found {value!r}")
        return value  # an int stays an int, as the simulation had it
    if hint is str:
        if not isinstance(value, str):
            raise ValueError(f"{where}: expected a string, found {value!r}")
        return value
    if hint is np.ndarray:
        array = np.array(value, dtype=float)
        if array.ndim != 1 or not np.isfinite(array).all():
            raise ValueError(f"{where}: expected a list of finite numbers")
        return array
    origin = get_origin(hint)
    if origin in (Union, types.UnionType):
        options = get_args(hint)
        if value is None and type(None) in options:
            return None
        inner = [o for o in options if o is not type(None)]
        return from_json(inner[0], value, where)
    if origin is tuple:
        args = get_args(hint)
        if not isinstance(value, list):
            raise ValueError(f"{where}: expected a list, found {value!r}")
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(from_json(args[0], v, f"{where}[{i}]") for i, v in enumerate(value))
        if len(value) != len(args):
            raise ValueError(f"{where}: expected {len(args)} values, found {len(value)}")
        return tuple(from_json(a, v, f"{where}[{i}]") for i, (a, v)
                     in enumerate(zip(args, value, strict=True)))
    if dataclasses.is_dataclass(hint):
        if not isinstance(value, dict):
            raise ValueError(f"{where}: expected an object, found {value!r}")
        hints = _hints(cast(type, hint))
        names = {f.name for f in dataclasses.fields(hint)}
        if set(value) - names:
            raise ValueError(f"{where}: unknown fields {sorted(set(value) - names)}")
        made = {f.name: from_json(hints[f.name], value[f.name], f"{where}.{f.name}")
                for f in dataclasses.fields(hint) if f.name in value}
        try:
            return cast(Any, hint)(**made)
        except TypeError as exc:
            raise ValueError(f"{where}: {exc}") from None
    raise ValueError(f"{where}: cannot decode {hint!r}")


@functools.cache
def _hints(cls: type) -> dict[str, Any]:
    """A dataclass's resolved field types (resolving them takes longer than a step)."""
    return get_type_hints(cls)


def encode_request(args: tuple[Any, ...], call: int = 0) -> bytes:
    return dumps({"call": call, "args": [to_json(a) for a in args]})


def decode_request(op: str, payload: bytes) -> tuple[int, tuple[Any, ...]]:
    """The call's number and the arguments of the request ``op``; ValueError (or BusError)
    saying what is wrong."""
    data = loads(payload)
    if not isinstance(data, dict) or not isinstance(data.get("args"), list):
        raise ValueError(f"{op}: expected {{\"call\": N, \"args\": [...]}}")
    call = data.get("call", 0)
    if not isinstance(call, int) or isinstance(call, bool):
        raise ValueError(f"{op}: call: expected a whole number, found {call!r}")
    kinds = OPS[op]
    if len(data["args"]) != len(kinds):
        raise ValueError(f"{op}: expected {len(kinds)} arguments, found {len(data['args'])}")
    return call, tuple(from_json(k, v, f"{op}.args[{i}]") for i, (k, v)
                       in enumerate(zip(kinds, data["args"], strict=True)))


class BusController(RemoteController):
    """The robot under test answering over the bus (see the module's docstring)."""

    def __init__(self, simulation: BusSession, mission: BusSession | None = None,
                 timeout: float | None = 5.0) -> None:
        self.timeout = timeout
        self.spec = "bus"
        self._broken = None
        self._feedback = None
        self._pending = False
        self._scan: LaserScan | None = None
        self._sessions = {"simulation": simulation, "mission": mission or simulation}
        self._lines: collections.deque[bytes] = collections.deque()
        self._op = ""
        self._calls = 0
        self.retries = 0
        """Calls sent again after finding nobody to answer."""
        self._closed = False
        self.name = "bus"
        self.context: ControllerContext | None = None
        """The context of the last reset (what `config/robot` answers)."""

    def load(self, wait: float) -> str:
        """Wait at most ``wait`` wall seconds for a robot to answer on the bus; its name.
        RunError when none does."""
        deadline = time.monotonic() + wait
        session = self._sessions["simulation"]
        key = f"{ROBOT_CALL}/load"
        while True:
            try:
                answer = session.call(key, encode_request((), -1), max(0.1, min(
                    1.0, deadline - time.monotonic())))
                break
            except BusError as exc:
                if not isinstance(exc, NoAnswer) or time.monotonic() >= deadline:
                    raise RunError(f"--bus: no robot answered on {session.endpoint} within "
                                   f"{wait:g} s: start `rei robot --bus {session.endpoint} "
                                   f"--controller ...` ({exc})") from None
                time.sleep(0.05)
        self._lines.extend(answer.split(b"\n"))
        value = self._answer("load", "load", None)
        if "error" in value:
            raise RunError(f"--bus: the robot could not load its controller: {value['error']}")
        self.name = str(value["ok"])[:200]
        return self.name

    def reset(self, context: ControllerContext) -> None:
        self.context = context
        super().reset(context)

    def _request(self, op: str, args: tuple[Any, ...]) -> bytes:
        self._op = op
        self._calls += 1
        return encode_request(args, self._calls)

    def _send(self, data: bytes, deadline: float | None) -> bool:
        """Call and keep the answer's lines; False when none came before the deadline. A
        call that finds nobody to answer (the router restarting, the robot reconnecting)
        is sent again after a bounded back-off (50 ms doubling to 1 s) until the deadline:
        the robot answers a call it has answered already with the same answer (its
        number), so a repeat never steps the controller twice."""
        session = self._sessions["mission" if self._op in MISSION_OPS else "simulation"]
        end = time.monotonic() + FOREVER if deadline is None else deadline
        pause = 0.05
        while True:
            try:
                answer = session.call(f"{ROBOT_CALL}/{self._op}", data,
                                      max(0.0, end - time.monotonic()))
                break
            except BusError:
                if time.monotonic() + pause >= end:
                    return False
                time.sleep(pause)
                pause = min(1.0, pause * 2)
                self.retries += 1
        self._lines.extend(answer.split(b"\n"))
        return True

    def _receive(self, what: str, deadline: float | None) -> bytes:
        if not self._lines:
            raise self._fault(f"controller {what}() got no answer line over the bus")
        return self._lines.popleft()

    def _late(self, what: str) -> str:
        return (f"the robot on the bus went silent: controller {what}() got no answer within "
                f"the watchdog's {self.timeout:g} s")

    def close(self) -> None:
        """Tell the robot the run is over (once; it may be gone already)."""
        if self._closed:
            return
        self._closed = True
        try:
            self._sessions["simulation"].call(f"{ROBOT_CALL}/close", encode_request(()), 2.0)
        except BusError:
            pass  # a robot that is gone needs no goodbye


def serve_robot(session: BusSession, load: Callable[[], Any], once: bool,
                stop: threading.Event, say: Callable[[str], None]) -> int:
    """Answer the robot contract's calls on ``session`` with a controller ``load`` makes
    (a fresh one per run) until ``stop`` is set (or, with ``once``, the first run closes);
    the number of runs served."""
    host = HostSide(lambda *args: load())
    lock = threading.Lock()
    runs = 0
    last: tuple[int, bytes] = (0, b"")
    """The last call's number and answer: a call sent again gets the same answer."""

    def handle(op: str, payload: bytes) -> bytes:
        nonlocal runs, last
        try:
            call, args = decode_request(op, payload)
        except (ValueError, BusError) as exc:
            raise BusError(f"a malformed {op} request: {exc}") from None
        with lock:
            if call > 0 and call == last[0]:
                return last[1]
            answer = _answer(op, args)
            last = (call, answer)
            return answer

    def _answer(op: str, args: tuple[Any, ...]) -> bytes:
        nonlocal runs, last
        if op == "close":
            runs += 1
            say(f"run {runs} ended")
            if once:
                stop.set()
            return b'{"ok": null}'
        if op == "load":  # a new run: its calls are numbered from 1 again
            last = (0, b"")
            say("a run began")
        return b"\n".join(host.answers(op, args))

    def handler(op: str) -> Callable[[bytes], bytes]:
        return lambda payload: handle(op, payload)

    for op in OPS:
        session.answer_raw(f"{ROBOT_CALL}/{op}", handler(op))
    while not stop.wait(0.2):
        pass
    return runs
