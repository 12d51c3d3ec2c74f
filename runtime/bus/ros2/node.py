"""A ROS 2 node on the wire of rmw_zenoh_cpp, without ROS: publishers, subscriptions, clients.

``RmwNode`` joins a ROS 2 graph through a Zenoh session the way rmw_zenoh_cpp does
(ros2/rmw_zenoh docs/design.md): a liveliness token for the node and one for each of its
publishers, subscriptions and service clients (``names.EntityToken``); messages are CDR
(rosbags) put on the topic's key expression with the 33-byte attachment
(``attachment.Attachment``); a service request is a Zenoh ``get`` on the service's key
expression with target ALL_COMPLETE, answered by the server's ``reply`` carrying the
request's sequence number and the client's GID back. A TRANSIENT_LOCAL publisher keeps its
last samples in a Zenoh advanced-publisher cache, which a late TRANSIENT_LOCAL subscription
(tf2's /tf_static listener) queries, as rmw_zenoh's own publishers do.

A message that cannot be decoded is counted and dropped, never raised into Zenoh's thread.
This module must never import pybullet or anything of the simulation: it carries messages.
"""

from __future__ import annotations

import itertools
import json
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from rei.runtime.bus.ros2 import attachment as wire
from rei.runtime.bus.ros2.errors import Ros2Error
from rei.runtime.bus.ros2.names import (
    DEFAULT_QOS,
    Distro,
    Durability,
    EntityKind,
    EntityToken,
    QosProfile,
    check_namespace,
    check_node_name,
    qualified,
    topic_keyexpr,
)
from rei.runtime.bus.ros2.types import type_hash, typestore

INSTALL_HINT = ("the ROS 2 profile needs the Zenoh Python package: "
                "pip install 'eclipse-zenoh>=1.10,<2' (or install REI with its test extra)")


def import_zenoh() -> Any:
    """The ``zenoh`` module, imported on first use (a heavy optional back end)."""
    try:
        import zenoh  # noqa: PLC0415
    except ImportError:
        raise Ros2Error(INSTALL_HINT) from None
    return zenoh


def client_config(router: str, config_file: str | None = None,
                  credentials: dict[str, Any] | None = None) -> Any:
    """A Zenoh client configuration connecting to ``router`` only (no multicast scouting),
    starting from ``config_file`` (a Zenoh JSON5 file) when given, and authenticating with
    ``credentials`` (a role's file of `rei bus`: user, password, and the CA for TLS)."""
    zenoh = import_zenoh()
    try:
        config = zenoh.Config.from_file(config_file) if config_file else zenoh.Config()
        if credentials is not None:
            config.insert_json5("transport/auth/usrpwd", json.dumps(
                {"user": credentials["user"], "password": credentials["password"]}))
            if isinstance(credentials.get("ca"), str):
                config.insert_json5("transport/link/tls/root_ca_certificate",
                                    json.dumps(credentials["ca"]))
        config.insert_json5("mode", '"client"')
        config.insert_json5("connect/endpoints", f'["{router}"]')
        config.insert_json5("scouting/multicast/enabled", "false")
        # an advanced publisher's cache (TRANSIENT_LOCAL) orders samples by timestamp, as
        # rmw_zenoh's DEFAULT_RMW_ZENOH_SESSION_CONFIG enables it
        config.insert_json5("timestamping/enabled", "true")
    except Exception as exc:  # noqa: BLE001  (zenoh reports a bad file or endpoint so)
        raise Ros2Error(f"zenoh configuration: {exc}") from None
    return config


def wall_ns() -> int:
    """The attachment's source timestamp: wall-clock nanoseconds, as rmw_zenoh writes it."""
    return time.time_ns()


@dataclass
class Received:
    """Counts of what a subscription or client got (for the run's summary and tests)."""

    messages: int = 0
    dropped: int = 0
    """Messages whose attachment or CDR did not decode."""
    last_error: str = ""


class Publisher:
    def __init__(self, node: RmwNode, token: EntityToken, handle: Any) -> None:
        self._node, self.token, self._handle = node, token, handle
        self._sequence = itertools.count(1)
        self.keyexpr = topic_keyexpr(token.domain, token.topic or "", token.msgtype or "",
                                     token.type_hash or "")

    def publish(self, message: Any) -> None:
        payload = bytes(self._node.store.serialize_cdr(message, self.token.msgtype or ""))
        meta = wire.Attachment(next(self._sequence), wall_ns(), self.token.gid).encode()
        self._handle.put(payload, attachment=meta)


def in_order(zenoh: Any, callback: Callable[[Any], None]) -> Any:
    """``callback`` run on the Zenoh thread that received the message, not on a Python thread
    of its own (zenoh-python's default): a session's messages from one peer then reach their
    callbacks in the order they came, across topics and replies. So what a stack said before
    its cmd_vel (a goal's status, a result) is known when that cmd_vel is, and a run does not
    depend on how the threads were scheduled. The callbacks only decode and store."""
    return zenoh.handlers.Callback(callback, indirect=False)


class TopicSubscription:
    """A subscription of a ROS 2 node to a topic on rmw_zenoh's wire (the bus's own is
    rei.runtime.bus.client.Subscription)."""

    def __init__(self, token: EntityToken, callback: Callable[[Any, wire.Attachment], None]
                 ) -> None:
        self.token, self._callback = token, callback
        self.received = Received()
        self.handle: Any = None

    def on_sample(self, store: Any, sample: Any) -> None:
        try:
            meta = wire.decode(None if sample.attachment is None
                               else sample.attachment.to_bytes())
            message = store.deserialize_cdr(sample.payload.to_bytes(), self.token.msgtype)
        except Exception as exc:  # noqa: BLE001  (anything a foreign peer sends)
            self.received.dropped += 1
            self.received.last_error = f"{type(exc).__name__}: {exc}"
            return
        self.received.messages += 1
        self._callback(message, meta)


@dataclass
class _Call:
    done: threading.Event = field(default_factory=threading.Event)
    response: Any = None
    error: str = ""


class Client:
    """A service client: requests go out as Zenoh queries, replies come back on any thread."""

    def __init__(self, node: RmwNode, token: EntityToken) -> None:
        self._node, self.token = node, token
        self._sequence = itertools.count(1)
        self.keyexpr = topic_keyexpr(token.domain, token.topic or "", token.msgtype or "",
                                     token.type_hash or "")
        self.received = Received()

    def call_async(self, request: Any, on_response: Callable[[Any], None],
                   on_error: Callable[[str], None] | None = None,
                   timeout: float = 86_400.0) -> int:
        """Send ``request``; ``on_response(response)`` runs on Zenoh's thread when the
        server answers (an action's get_result may answer much later: the default timeout
        is a day, as rmw_zenoh waits "the largest supported value")."""
        zenoh = import_zenoh()
        base = self.token.msgtype or ""
        payload = bytes(self._node.store.serialize_cdr(request, f"{base}_Request"))
        sequence = next(self._sequence)
        meta = wire.Attachment(sequence, wall_ns(), self.token.gid).encode()

        def reply(answer: Any) -> None:
            if answer.ok is None:
                self.received.dropped += 1
                message = f"error reply: {answer.err.payload.to_string()}"
                self.received.last_error = message
                if on_error is not None:
                    on_error(message)
                return
            sample = answer.ok
            try:
                back = wire.decode(None if sample.attachment is None
                                   else sample.attachment.to_bytes())
                if back.sequence_number != sequence:
                    raise Ros2Error(f"reply to request {sequence} carries sequence number "
                                    f"{back.sequence_number}")
                response = self._node.store.deserialize_cdr(sample.payload.to_bytes(),
                                                            f"{base}_Response")
            except Exception as exc:  # noqa: BLE001  (anything a foreign server sends)
                self.received.dropped += 1
                self.received.last_error = f"{type(exc).__name__}: {exc}"
                if on_error is not None:
                    on_error(self.received.last_error)
                return
            self.received.messages += 1
            on_response(response)

        self._node.session.get(self.keyexpr, in_order(zenoh, reply), payload=payload,
                               attachment=meta, target=zenoh.QueryTarget.ALL_COMPLETE,
                               consolidation=zenoh.ConsolidationMode.NONE, timeout=timeout)
        return sequence

    def call(self, request: Any, timeout: float) -> Any:
        """Send ``request`` and wait up to ``timeout`` wall seconds for the response."""
        state = _Call()

        def answered(response: Any) -> None:
            state.response = response
            state.done.set()

        def failed(message: str) -> None:
            state.error = message
            state.done.set()

        self.call_async(request, answered, failed, timeout)
        if not state.done.wait(timeout):
            raise Ros2Error(f"service {self.token.topic}: no response within {timeout:g} s "
                            f"(is the server up and connected to the same router?)")
        if state.error:
            raise Ros2Error(f"service {self.token.topic}: {state.error}")
        return state.response


class RmwNode:
    """A ROS 2 node as rmw_zenoh_cpp announces it, over an open Zenoh session."""

    def __init__(self, session: Any, name: str, *, namespace: str = "/", domain: int = 0,
                 distro: Distro = Distro.JAZZY, enclave: str = "/") -> None:
        self.session = session
        self.name, self.namespace = check_node_name(name), check_namespace(namespace)
        self.domain, self.distro, self.enclave = domain, distro, enclave
        self.store = typestore(distro)
        self._session_id = str(session.zid())
        self._entity_ids = itertools.count(10)  # rmw_zenoh's node 0 starts its entities at 10
        self._declared: list[Any] = []
        self.token = EntityToken(domain, self._session_id, 0, 0, EntityKind.NODE,
                                 self.namespace, self.name, enclave)
        self._declared.append(session.liveliness().declare_token(self.token.keyexpr))

    def _entity(self, kind: EntityKind, topic: str, msgtype: str, qos: QosProfile
                ) -> EntityToken:
        return EntityToken(self.domain, self._session_id, 0, next(self._entity_ids), kind,
                           self.namespace, self.name, self.enclave,
                           qualified(self.namespace, topic), msgtype,
                           type_hash(msgtype, self.distro), qos)

    def publisher(self, topic: str, msgtype: str, qos: QosProfile = DEFAULT_QOS) -> Publisher:
        zenoh = import_zenoh()
        token = self._entity(EntityKind.PUBLISHER, topic, msgtype, qos)
        key = topic_keyexpr(self.domain, token.topic or "", msgtype, token.type_hash or "")
        if qos.durability == Durability.TRANSIENT_LOCAL:
            handle = zenoh.ext.declare_advanced_publisher(
                self.session, key, cache=zenoh.ext.CacheConfig(max_samples=qos.depth),
                publisher_detection=True)
        else:
            handle = self.session.declare_publisher(key)
        self._declared.append(handle)
        self._declared.append(self.session.liveliness().declare_token(token.keyexpr))
        return Publisher(self, token, handle)

    def subscription(self, topic: str, msgtype: str,
                     callback: Callable[[Any, wire.Attachment], None],
                     qos: QosProfile = DEFAULT_QOS) -> TopicSubscription:
        zenoh = import_zenoh()
        token = self._entity(EntityKind.SUBSCRIPTION, topic, msgtype, qos)
        key = topic_keyexpr(self.domain, token.topic or "", msgtype, token.type_hash or "")
        subscription = TopicSubscription(token, callback)
        store = self.store

        def handler(sample: Any) -> None:
            subscription.on_sample(store, sample)

        if qos.durability == Durability.TRANSIENT_LOCAL:
            subscription.handle = zenoh.ext.declare_advanced_subscriber(
                self.session, key, in_order(zenoh, handler),
                history=zenoh.ext.HistoryConfig(detect_late_publishers=True))
        else:
            subscription.handle = self.session.declare_subscriber(key, in_order(zenoh, handler))
        self._declared.append(subscription.handle)
        self._declared.append(self.session.liveliness().declare_token(token.keyexpr))
        return subscription

    def client(self, service: str, srvtype: str, qos: QosProfile = DEFAULT_QOS) -> Client:
        token = self._entity(EntityKind.CLIENT, service, srvtype, qos)
        self._declared.append(self.session.liveliness().declare_token(token.keyexpr))
        return Client(self, token)

    def graph(self, timeout: float = 1.0) -> list[EntityToken]:
        """The ROS graph of this domain as its liveliness tokens say now (malformed tokens
        of foreign peers are skipped)."""
        from rei.runtime.bus.ros2.names import ADMIN_SPACE, parse_token  # noqa: PLC0415
        found = []
        for reply in self.session.liveliness().get(f"{ADMIN_SPACE}/{self.domain}/**",
                                                   timeout=timeout):
            if reply.ok is None:
                continue
            try:
                found.append(parse_token(str(reply.ok.key_expr)))
            except Ros2Error:
                continue
        return found

    def close(self) -> None:
        """Undeclare every entity (its liveliness token goes, so the graph forgets it)."""
        for handle in reversed(self._declared):
            try:
                handle.undeclare()
            except Exception:  # noqa: BLE001,S110  (a session already closed)
                pass
        self._declared.clear()
