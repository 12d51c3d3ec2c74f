"""ROS 2 names as rmw_zenoh_cpp puts them on the wire: key expressions and liveliness tokens.

rmw_zenoh_cpp (ros2/rmw_zenoh, docs/design.md, "Topic and Service name mapping to Zenoh key
expressions" and "Graph Cache"; rmw_zenoh_cpp/src/detail/liveliness_utils.cpp) maps

- a topic or service to ``<domain_id>/<fully qualified name without its outer slashes>/
  <DDS type name>/<type hash>``, e.g. ``0/chatter/std_msgs::msg::dds_::String_/RIHS01_df66…``;
- every node, publisher, subscription, service server and client to a liveliness token
  ``@ros2_lv/<domain_id>/<session id>/<node id>/<entity id>/<NN|MP|MS|SS|SC>/<enclave>/
  <namespace>/<node name>[/<topic>/<type>/<type hash>/<qos>]`` with every ``/`` inside a
  part replaced by ``%`` (an empty namespace is ``%``), and the QoS in the compact form of
  ``qos_to_keyexpr`` (a field equal to rmw_zenoh's default is left empty).

This module only builds and parses those strings (and validates the ROS names that go into
them, naming what was expected and what was found); it must never open a session.
"""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass
from enum import IntEnum, StrEnum

from rei.runtime.bus.ros2.errors import Ros2Error

ADMIN_SPACE = "@ros2_lv"
"""The hermetic prefix of every rmw_zenoh liveliness token (``*`` and ``**`` never match it)."""

HASH_NOT_SUPPORTED = "TypeHashNotSupported"
"""What rmw_zenoh_cpp on ROS 2 Humble writes where later distributions write a RIHS01 hash."""

_TOKEN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


class Distro(StrEnum):
    """The ROS 2 distribution of the stack under test: it decides the type hash form and
    the action types' definitions (Nav2's NavigateToPose result changed in Jazzy)."""

    HUMBLE = "humble"
    """Type hashes are ``TypeHashNotSupported`` (REP 2011 came with Iron)."""
    JAZZY = "jazzy"
    """Type hashes are RIHS01 (REP 2011), computed from the type descriptions; the same
    message definitions hold for Kilted."""


class EntityKind(StrEnum):
    NODE = "NN"
    PUBLISHER = "MP"
    SUBSCRIPTION = "MS"
    SERVICE = "SS"
    CLIENT = "SC"


class Reliability(IntEnum):
    """rmw_qos_reliability_policy_e (ros2/rmw, rmw/types.h)."""

    RELIABLE = 1
    BEST_EFFORT = 2


class Durability(IntEnum):
    """rmw_qos_durability_policy_e (ros2/rmw, rmw/types.h)."""

    TRANSIENT_LOCAL = 1
    VOLATILE = 2


class History(IntEnum):
    """rmw_qos_history_policy_e (ros2/rmw, rmw/types.h)."""

    KEEP_LAST = 1
    KEEP_ALL = 2


@dataclass(frozen=True)
class QosProfile:
    """The QoS policies REI's endpoints use (deadline, lifespan and liveliness stay at
    rmw_zenoh's defaults: infinite, infinite, automatic)."""

    reliability: Reliability = Reliability.RELIABLE
    durability: Durability = Durability.VOLATILE
    history: History = History.KEEP_LAST
    depth: int = 10

    def keyexpr(self) -> str:
        """The compact form of rmw_zenoh_cpp's ``qos_to_keyexpr``: ``rel:dur:hist,depth:
        deadline_s,ns:lifespan_s,ns:liveliness,lease_s,ns`` with rmw_zenoh's defaults
        (reliable, volatile, keep last, depth 42, infinite durations, automatic) left empty."""
        default = RMW_ZENOH_DEFAULT_QOS
        rel = "" if self.reliability == default.reliability else str(int(self.reliability))
        dur = "" if self.durability == default.durability else str(int(self.durability))
        hist = "" if self.history == default.history else str(int(self.history))
        depth = "" if self.depth == default.depth else str(self.depth)
        return f"{rel}:{dur}:{hist},{depth}:,:,:,,"


RMW_ZENOH_DEFAULT_QOS = QosProfile(depth=42)
"""rmw_zenoh_cpp/src/detail/qos.cpp: keep last 42, reliable, volatile."""

SENSOR_QOS = QosProfile(reliability=Reliability.BEST_EFFORT, depth=5)
"""rmw_qos_profile_sensor_data: what Nav2's costmaps and AMCL subscribe /scan with."""
LATCHED_QOS = QosProfile(durability=Durability.TRANSIENT_LOCAL, depth=1)
"""tf2's static broadcaster and an action server's status topic: the last sample kept."""
DEFAULT_QOS = QosProfile()
"""rmw_qos_profile_default: reliable, volatile, keep last 10."""


def dds_type_name(msgtype: str) -> str:
    """``pkg/msg/Type`` -> ``pkg::msg::dds_::Type_`` (the name in a key expression).

    Services are named by their base type (``pkg/srv/AddTwoInts`` ->
    ``pkg::srv::dds_::AddTwoInts_``), as rmw_zenoh strips ``Request_`` from the request's
    type name; an action's services and topics by theirs
    (``nav2_msgs/action/NavigateToPose_SendGoal``)."""
    parts = msgtype.split("/")
    if len(parts) != 3 or not all(_TOKEN.fullmatch(p) for p in parts) \
            or parts[1] not in ("msg", "srv", "action"):
        raise Ros2Error(f"ROS 2 type: expected package/msg|srv|action/Name, found '{msgtype}'")
    return f"{parts[0]}::{parts[1]}::dds_::{parts[2]}_"


def check_namespace(namespace: str) -> str:
    """A ROS namespace ('/' or '/a/b'), or Ros2Error saying what is wrong with it."""
    if namespace == "/":
        return namespace
    tokens = namespace.split("/")
    if not namespace.startswith("/") or not all(_TOKEN.fullmatch(t) for t in tokens[1:]):
        raise Ros2Error(f"namespace: expected '/' or '/name[/name...]' (letters, digits, _), "
                        f"found '{namespace}'")
    return namespace


def check_node_name(name: str) -> str:
    if not _TOKEN.fullmatch(name):
        raise Ros2Error(f"node name: expected letters, digits and _ (not starting with a "
                        f"digit), found '{name}'")
    return name


def qualified(namespace: str, name: str) -> str:
    """The fully qualified name of topic or service ``name`` in ``namespace``: an absolute
    ``/name`` stays as it is, a relative one goes under the namespace (ROS 2 name rules)."""
    check_namespace(namespace)
    full = name if name.startswith("/") else \
        ("/" + name if namespace == "/" else f"{namespace}/{name}")
    tokens = full.split("/")[1:]
    if not tokens or not all(_TOKEN.fullmatch(t) for t in tokens):
        raise Ros2Error(f"topic or service name: expected /name[/name...] (letters, digits, "
                        f"_), found '{name}'")
    return full


def topic_keyexpr(domain: int, fq_name: str, msgtype: str, type_hash: str) -> str:
    """The key expression data of topic (or service) ``fq_name`` travels on."""
    if not 0 <= domain <= 232:
        raise Ros2Error(f"domain id: expected 0..232 (ROS_DOMAIN_ID), found {domain}")
    return f"{domain}/{fq_name.strip('/')}/{dds_type_name(msgtype)}/{type_hash}"


def mangle(name: str) -> str:
    """rmw_zenoh's ``mangle_name``: every ``/`` becomes ``%``."""
    return name.replace("/", "%")


def demangle(name: str) -> str:
    return name.replace("%", "/")


@dataclass(frozen=True)
class EntityToken:
    """One rmw_zenoh liveliness token: who is in the ROS graph (a node, or one of its
    publishers, subscriptions, service servers or clients)."""

    domain: int
    session_id: str
    node_id: int
    entity_id: int
    kind: EntityKind
    namespace: str
    node_name: str
    enclave: str = "/"
    topic: str | None = None
    """Fully qualified topic or service name (None for a node)."""
    msgtype: str | None = None
    """ROS type name ``pkg/msg/Type`` (a service's or action service's base type)."""
    type_hash: str | None = None
    qos: QosProfile | None = None
    qos_text: str | None = None
    """The QoS part as it was on the wire (kept when parsed, for faithful comparison)."""

    @property
    def keyexpr(self) -> str:
        parts = [ADMIN_SPACE, str(self.domain), self.session_id, str(self.node_id),
                 str(self.entity_id), self.kind.value, mangle(self.enclave),
                 mangle(self.namespace), mangle(self.node_name)]
        if self.kind != EntityKind.NODE:
            if self.topic is None or self.msgtype is None or self.type_hash is None:
                raise Ros2Error(f"liveliness token of a {self.kind.name.lower()}: expected "
                                f"a topic, type and type hash, found none")
            qos = self.qos_text if self.qos_text is not None else \
                (self.qos or DEFAULT_QOS).keyexpr()
            parts += [mangle(self.topic), mangle(dds_type_name(self.msgtype)),
                      mangle(self.type_hash), qos]
        return "/".join(parts)

    @property
    def gid(self) -> bytes:
        """The entity's 16-byte GID, a hash of its token as rmw_zenoh makes it (there with
        XXH3-128; peers only carry a GID along, never recompute it, so any stable 16-byte
        hash of the token serves)."""
        return hashlib.blake2b(self.keyexpr.encode(), digest_size=16).digest()


def parse_token(keyexpr: str) -> EntityToken:
    """An rmw_zenoh liveliness token read back; Ros2Error naming the part that is wrong."""
    parts = keyexpr.split("/")
    if len(parts) < 9 or parts[0] != ADMIN_SPACE:
        raise Ros2Error(f"liveliness token: expected {ADMIN_SPACE}/<domain>/<session>/<node>/"
                        f"<entity>/<kind>/<enclave>/<namespace>/<node name>[/...], found "
                        f"'{keyexpr}'")
    if any(not p for p in parts):
        raise Ros2Error(f"liveliness token: found an empty part in '{keyexpr}'")
    try:
        domain, node_id, entity_id = int(parts[1]), int(parts[3]), int(parts[4])
    except ValueError:
        raise Ros2Error(f"liveliness token: expected numeric domain, node and entity ids, "
                        f"found '{keyexpr}'") from None
    try:
        kind = EntityKind(parts[5])
    except ValueError:
        raise Ros2Error(f"liveliness token: expected kind NN, MP, MS, SS or SC, found "
                        f"'{parts[5]}'") from None
    base = {"domain": domain, "session_id": parts[2], "node_id": node_id,
            "entity_id": entity_id, "kind": kind, "enclave": demangle(parts[6]),
            "namespace": demangle(parts[7]), "node_name": demangle(parts[8])}
    if kind == EntityKind.NODE:
        return EntityToken(**base)  # type: ignore[arg-type]
    if len(parts) != 13:
        raise Ros2Error(f"liveliness token of kind {kind.value}: expected 13 parts (topic, "
                        f"type, type hash, qos after the node name), found {len(parts)}")
    dds = demangle(parts[10])
    match = re.fullmatch(r"([A-Za-z0-9_]+)::(msg|srv|action)::dds_::([A-Za-z0-9_]+)_", dds)
    if match is None:
        raise Ros2Error(f"liveliness token: expected a DDS type name pkg::msg::dds_::Type_, "
                        f"found '{dds}'")
    return EntityToken(**base, topic=demangle(parts[9]),  # type: ignore[arg-type]
                       msgtype="/".join(match.groups()), type_hash=demangle(parts[11]),
                       qos_text=parts[12])
