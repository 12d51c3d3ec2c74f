"""Joining the bus: ``connect`` and ``BusSession``, the one interface components use.

A session is one role's connection to the router (a Zenoh client session, authenticated
with that role's credentials). It publishes the stamped messages of
``rei.runtime.messages`` on their keys (``rei.runtime.bus.schema``), delivers the messages of
the topics it subscribes to decoded, asks for and answers configuration, and carries the raw
payloads of the other keys of the schema (the trace stream, the robot's calls). Before doing
anything it checks that its role may (``RoleAccess.check``): the router would refuse it
anyway, silently; the session says so in one line. A payload that cannot be decoded is
dropped and counted (``dropped``, the last reason in ``last_drop``), never raised into the
receiving thread. Publication is reliable with blocking congestion control: a slow reader
slows the writer down instead of losing messages (lock-step runs must be exact). This
module must never import the simulator.
"""

from __future__ import annotations

import json
import os
import socket
import threading
import time
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any, TypeAlias

from rei.runtime.bus.access import DEFAULT_ACCESS, AccessRules
from rei.runtime.bus.errors import BusError, NoAnswer, zenoh_module
from rei.runtime.bus.router import check_private
from rei.runtime.bus.schema import (
    ALL,
    PREFIX,
    config_key,
    decode_message,
    dumps,
    encode_message,
    loads,
    topic_key,
    topic_of,
)
from rei.runtime.messages import LoopMessage

Message: TypeAlias = LoopMessage
"""What ``subscribe`` delivers: a message of ``rei.runtime.messages``."""

CREDENTIALS_ENV = "REI_BUS_CREDENTIALS"
"""The bus folder (or one role's file) when ``connect`` is given none."""

QUERY_TIMEOUT = 5.0
"""Wall seconds a configuration query waits for its answer."""


def parse_endpoint(endpoint: str) -> tuple[str, str, int]:
    """(scheme, host, port) of ``tcp/HOST:PORT``, ``tls/HOST:PORT`` or ``HOST:PORT``."""
    text = endpoint.strip()
    scheme = "tcp"
    if "/" in text:
        scheme, _, text = text.partition("/")
    host, sep, port_text = text.rpartition(":")
    host = host.strip("[]")
    if scheme not in ("tcp", "tls") or not sep or not host or not port_text.isdigit() \
            or not 0 < int(port_text) < 65536:
        raise BusError(f"--bus: an endpoint expected as tcp/HOST:PORT, tls/HOST:PORT or "
                       f"HOST:PORT (as `rei bus` prints it), found {endpoint!r}")
    return scheme, host, int(port_text)


def read_credentials(role: str, credentials: Path | None) -> dict[str, Any]:
    """The user, password (and CA) of ``role`` from a role's file or the bus folder."""
    if credentials is None:
        env = os.environ.get(CREDENTIALS_ENV)
        if not env:
            raise BusError(f"the {role} role needs credentials: pass --credentials (the folder "
                           f"`rei bus` printed) or set {CREDENTIALS_ENV}")
        credentials = Path(env)
    path = credentials / f"{role}.json" if credentials.is_dir() else credentials
    try:
        check_private(path)
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise BusError(f"{path}: the {role} role's credentials expected, found no file") \
            from None
    except (OSError, ValueError) as exc:
        raise BusError(f"{path}: the {role} role's credentials unreadable: {exc}") from None
    if not isinstance(data, dict) or not all(isinstance(data.get(k), str)
                                             for k in ("user", "password")):
        raise BusError(f"{path}: credentials expected as a JSON object with \"user\" and "
                       f"\"password\", found something else")
    if data.get("role", role) != role:
        raise BusError(f"{path}: credentials of the {role} role expected, found the "
                       f"{data.get('role')} role's")
    return data


def _reachable(host: str, port: int) -> bool:
    try:
        with socket.create_connection((host, port), timeout=1.0):
            return True
    except OSError:
        return False


class Subscription:
    """One ``subscribe``'s subscribers; ``close`` ends the deliveries."""

    def __init__(self, subscribers: list[Any]) -> None:
        self._subscribers = subscribers

    def close(self) -> None:
        subscribers, self._subscribers = self._subscribers, []
        for s in subscribers:
            s.undeclare()


class BusSession:
    """One role's connection to the router (see the module's docstring)."""

    def __init__(self, session: Any, role: str, endpoint: str,
                 access: AccessRules = DEFAULT_ACCESS) -> None:
        self._zenoh: Any = zenoh_module()
        self._session = session
        self.role = role
        self.endpoint = endpoint
        self.access = access.role(role)
        self._publishers: dict[str, Any] = {}
        self._lock = threading.Lock()
        self._queryables: list[Any] = []
        self.dropped = 0
        """Payloads received that could not be decoded (too big, not JSON, not a message)."""
        self.last_drop = ""
        """Why the last one was dropped."""
        self.callback_errors = 0
        """Exceptions a subscriber's callback raised (kept out of Zenoh's threads)."""
        self._allowed: set[tuple[str, str]] = set()
        """(action, key) pairs the role was found to be allowed (checked once)."""

    # -- messages ---------------------------------------------------------------------------

    def publish(self, message: Message) -> None:
        """Send ``message`` on its topic's key."""
        self.put(topic_key(message.TOPIC), encode_message(message))

    def put(self, key: str, payload: bytes) -> None:
        """Send a raw payload on ``key`` (a key of the schema that is not a message topic)."""
        self._publisher(key).put(payload)

    def await_readers(self, key: str, timeout: float) -> bool:
        """Wait until a subscriber elsewhere matches ``key`` (a topic or a key), at most
        ``timeout`` wall seconds; whether one does. What is published before a reader's
        subscription reaches the router is not delivered to it: a run that must be seen
        from its first message waits for its readers first."""
        if not key.startswith(PREFIX + "/"):
            key = topic_key(key)
        publisher = self._publisher(key)
        deadline = time.monotonic() + timeout
        while not publisher.matching_status.matching:
            if time.monotonic() >= deadline:
                return False
            time.sleep(0.01)
        return True

    def _publisher(self, key: str) -> Any:
        self._check("publish", key)
        publisher = self._publishers.get(key)
        if publisher is None:
            z = self._zenoh
            publisher = self._session.declare_publisher(
                key, congestion_control=z.CongestionControl.BLOCK,
                reliability=z.Reliability.RELIABLE)
            self._publishers[key] = publisher
        return publisher

    def subscribe(self, topics: Iterable[str] | None,
                  callback: Callable[[str, Message], None]) -> Subscription:
        """Call ``callback(topic, message)`` for each message of ``topics`` (None: all),
        decoded; an undecodable payload is dropped and counted."""
        keys = [ALL] if topics is None else [topic_key(t) for t in topics]

        def deliver(key: str, payload: bytes) -> None:
            try:
                message = decode_message(key, payload)
            except BusError as exc:
                self._drop(str(exc))
                return
            callback(message.TOPIC, message)

        def on_raw(key: str, payload: bytes) -> None:
            if topic_of(key) is not None:  # the schema's other keys are not messages
                deliver(key, payload)

        return Subscription([self._declare(k, on_raw if topics is None else deliver)
                             for k in keys])

    def subscribe_raw(self, key: str, callback: Callable[[str, bytes], None]) -> Subscription:
        """Call ``callback(key, payload)`` for each payload on ``key`` (may hold wildcards)."""
        return Subscription([self._declare(key, callback)])

    def _check(self, action: str, key: str) -> None:
        if (action, key) not in self._allowed:
            self.access.check(action, key)
            self._allowed.add((action, key))

    def _declare(self, key: str, callback: Callable[[str, bytes], None]) -> Any:
        self._check("subscribe", key)

        def handler(sample: Any) -> None:
            try:
                callback(str(sample.key_expr), sample.payload.to_bytes())
            except Exception as exc:  # noqa: BLE001  (never into Zenoh's thread)
                self.callback_errors += 1
                self.last_drop = f"callback raised {type(exc).__name__}: {exc}"

        return self._session.declare_subscriber(key, handler)

    def _drop(self, reason: str) -> None:
        with self._lock:
            self.dropped += 1
            self.last_drop = reason

    # -- configuration ----------------------------------------------------------------------

    def query(self, name: str, timeout: float = QUERY_TIMEOUT) -> dict[str, Any]:
        """The configuration ``name`` (``CONFIG_NAMES``) as its answerer gives it."""
        key = config_key(name)
        deadline = time.monotonic() + timeout
        pause, wait = 0.02, 1.0
        # The answerer may not have joined yet, its queryable not reached the router, or the
        # router may route an ask to an answerer that just left: ask again (pauses of 20 ms
        # doubling to 0.5 s; each ask waits 1 s doubling to 8 s) until the deadline. A
        # configuration answer is a ready payload: it takes milliseconds when it comes.
        while True:
            try:
                data = self.call(key, b"", max(0.0, min(wait, deadline - time.monotonic())))
                break
            except NoAnswer:
                if time.monotonic() + pause >= deadline:
                    raise BusError(f"{key}: no answer within {timeout:g} s (nobody answers "
                                   f"it, or the router's rules keep the {self.role} role "
                                   f"from asking)") from None
                time.sleep(pause)
                pause, wait = min(0.5, pause * 2), min(8.0, wait * 2)
        answer = loads(data)
        if not isinstance(answer, dict):
            raise BusError(f"{key}: a JSON object expected as the answer, found "
                           f"{type(answer).__name__}")
        return answer

    def call(self, key: str, payload: bytes, timeout: float) -> bytes:
        """One request/answer on ``key``: the first answer's payload; ``BusError`` when
        none comes within ``timeout`` wall seconds."""
        self._check("query", key)
        z = self._zenoh
        try:
            replies = self._session.get(key, payload=payload, timeout=timeout,
                                        target=z.QueryTarget.BEST_MATCHING,
                                        consolidation=z.ConsolidationMode.NONE)
            for reply in replies:
                if reply.ok is not None:
                    data: bytes = reply.ok.payload.to_bytes()
                    return data
                raise BusError(f"{key}: the answerer refused: "
                               f"{reply.err.payload.to_bytes().decode('utf-8', 'replace')}")
        except z.ZError as exc:
            raise BusError(f"{key}: {exc}") from None
        raise NoAnswer(f"{key}: no answer within {timeout:g} s (nobody answers it, or the "
                       f"router's rules keep the {self.role} role from asking)")

    def answer(self, name: str, provider: Callable[[], dict[str, Any]]) -> None:
        """Answer queries for the configuration ``name`` with ``provider()``'s object."""
        payload = dumps(provider())
        self.answer_raw(config_key(name), lambda _request: payload)

    def answer_raw(self, key: str, handler: Callable[[bytes], bytes]) -> None:
        """Answer every query on ``key`` with ``handler(request payload)``."""
        self._check("answer", key)

        def on_query(query: Any) -> None:
            request = query.payload.to_bytes() if query.payload is not None else b""
            try:
                reply = handler(request)
            except Exception as exc:  # noqa: BLE001  (told to the asker, never raised here)
                query.reply_err(f"{type(exc).__name__}: {exc}".encode())
                return
            query.reply(query.key_expr, reply)

        self._queryables.append(self._session.declare_queryable(key, on_query))

    @property
    def zenoh_session(self) -> Any:
        """The Zenoh session underneath, for a profile that speaks Zenoh itself (the ROS 2
        profile's liveliness tokens and attachments). The router's rules bind it all the
        same; this session's own checks do not."""
        return self._session

    # -- life -------------------------------------------------------------------------------

    def close(self) -> None:
        session, self._session = self._session, None
        if session is not None:
            session.close()

    def __enter__(self) -> BusSession:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def connect(endpoint: str, *, role: str, credentials: Path | None = None,
            access: AccessRules = DEFAULT_ACCESS) -> BusSession:
    """Join the bus at ``endpoint`` as ``role`` with the credentials `rei bus` wrote (the
    bus folder or the role's file; default ``$REI_BUS_CREDENTIALS``)."""
    access.role(role)  # an unknown role is refused before anything else
    scheme, host, port = parse_endpoint(endpoint)
    secret = read_credentials(role, credentials)
    zenoh: Any = zenoh_module()
    address = f"[{host}]" if ":" in host else host
    locator = f"{scheme}/{address}:{port}"
    config: dict[str, Any] = {
        "mode": "client",
        "connect": {"endpoints": [locator]},
        "scouting": {"multicast": {"enabled": False}, "gossip": {"enabled": False}},
        "transport": {"auth": {"usrpwd": {"user": secret["user"],
                                          "password": secret["password"]}}},
        "adminspace": {"enabled": False},
    }
    if scheme == "tls":
        if not isinstance(secret.get("ca"), str):
            raise BusError(f"a TLS bus needs the CA certificate: the {role} role's "
                           f"credentials name none")
        config["transport"]["link"] = {"tls": {"root_ca_certificate": secret["ca"]}}
    try:
        session = zenoh.open(zenoh.Config.from_json5(json.dumps(config)))
    except zenoh.ZError:
        if _reachable(host, port):
            raise BusError(f"the bus at {locator} refused the {role} role's credentials "
                           f"(user {secret['user']})") from None
        raise BusError(f"no bus at {locator}: is `rei bus` running there?") from None
    return BusSession(session, role, locator, access)
