"""The ROS 2 profile of REI's bus: which key expressions each side owns, for the router's rules.

The robot-facing interface (the topics of ``rei.runtime.messages.ros`` plus /clock, Nav2's
``navigate_to_pose`` action and the ``goal_pose`` topic) on rmw_zenoh_cpp's key expressions,
split by who may do what, so the bus's access-control configuration can include them:

- ``simulation`` (REI's adapter) publishes /clock, scan, odom, tf, tf_static and goal_pose,
  sends the action's requests (queries) and subscribes cmd_vel and the action's topics;
- ``robot`` (the ROS 2 stack) publishes cmd_vel and the action's feedback and status,
  answers the action's requests (queryables and replies), and must never publish what the
  simulation measures (``deny_put``: a stack that forges /odom or /clock is refused by the
  router, not trusted to be polite). Its own internal graph (Nav2's nodes talking to each
  other through the router, parameters, /rosout) is everything else in its domain
  (``graph``); the bus decides whether to open it.

Both sides declare liveliness tokens under ``@ros2_lv/<domain>/**``. ``with_ros2`` adds all
of it to the bus's rules (``rei.runtime.bus.access``), so `rei bus` enforces the profile
with the same router. This module only computes key expressions; it must never open a
session or write a configuration file.
"""

from __future__ import annotations

from dataclasses import dataclass

from rei.runtime.bus.access import AccessRules
from rei.runtime.bus.ros2.names import ADMIN_SPACE, Distro, qualified, topic_keyexpr
from rei.runtime.bus.ros2.nav2 import ACTION
from rei.runtime.bus.ros2.types import (
    CANCEL_GOAL,
    CLOCK,
    GOAL_STATUS_ARRAY,
    NAVIGATE_TO_POSE,
    POSE_STAMPED,
    type_hash,
)
from rei.runtime.messages.ros import TOPICS


@dataclass(frozen=True)
class RoleKeys:
    """What one role may do, as Zenoh key expressions (no wildcards but ``graph``'s)."""

    role: str
    put: tuple[str, ...]
    """Publish (Zenoh put)."""
    subscribe: tuple[str, ...]
    query: tuple[str, ...]
    """Send service requests (Zenoh get)."""
    reply: tuple[str, ...]
    """Serve requests (declare a queryable and reply)."""
    liveliness: str
    deny_put: tuple[str, ...] = ()
    """Never publish here, whatever broader rule (``graph``) allows."""
    graph: str = ""
    """The rest of the role's ROS domain, for its own nodes' traffic."""


@dataclass(frozen=True)
class Endpoint:
    topic: str
    """Fully qualified name."""
    msgtype: str
    keyexpr: str


def endpoints(domain: int = 0, namespace: str = "/", distro: Distro = Distro.JAZZY
              ) -> dict[str, Endpoint]:
    """Every endpoint of the profile by a short name (clock, scan, ..., send_goal)."""

    def one(name: str, msgtype: str) -> Endpoint:
        fq = qualified(namespace, name)
        return Endpoint(fq, msgtype, topic_keyexpr(domain, fq, msgtype,
                                                   type_hash(msgtype, distro)))

    action = f"{ACTION}/_action"
    found = {"clock": one("/clock", CLOCK)}
    for topic in ("/scan", "/odom", "/tf", "/tf_static", "/cmd_vel"):
        found[topic.lstrip("/")] = one(topic.lstrip("/"), TOPICS[topic])
    found["goal_pose"] = one("goal_pose", POSE_STAMPED)
    found["send_goal"] = one(f"{action}/send_goal", f"{NAVIGATE_TO_POSE}_SendGoal")
    found["cancel_goal"] = one(f"{action}/cancel_goal", CANCEL_GOAL)
    found["get_result"] = one(f"{action}/get_result", f"{NAVIGATE_TO_POSE}_GetResult")
    found["feedback"] = one(f"{action}/feedback", f"{NAVIGATE_TO_POSE}_FeedbackMessage")
    found["status"] = one(f"{action}/status", GOAL_STATUS_ARRAY)
    return found


def access_rules(domain: int = 0, namespace: str = "/", distro: Distro = Distro.JAZZY
                 ) -> dict[str, RoleKeys]:
    """The profile's key expressions per role: ``simulation`` and ``robot``."""
    e = {name: point.keyexpr for name, point in endpoints(domain, namespace, distro).items()}
    sensors = tuple(e[n] for n in ("clock", "scan", "odom", "tf", "tf_static", "goal_pose"))
    services = tuple(e[n] for n in ("send_goal", "cancel_goal", "get_result"))
    action_topics = (e["feedback"], e["status"])
    liveliness = f"{ADMIN_SPACE}/{domain}/**"
    return {
        "simulation": RoleKeys("simulation", put=sensors,
                               subscribe=(e["cmd_vel"], *action_topics), query=services,
                               reply=(), liveliness=liveliness),
        "robot": RoleKeys("robot", put=(e["cmd_vel"], *action_topics),
                          subscribe=sensors, query=(), reply=services, liveliness=liveliness,
                          deny_put=sensors, graph=f"{domain}/**"),
    }


def with_ros2(access: AccessRules, domain: int = 0, namespace: str = "/",
              distro: Distro = Distro.JAZZY) -> AccessRules:
    """The bus's access rules with the ROS 2 profile's keys added: the ``simulation`` role
    (REI's adapter) and the ``robot`` role (the ROS 2 stack) as ``access_rules`` splits them,
    and read access to the profile's topics for the ``monitor`` and ``viewer`` roles.

    A TRANSIENT_LOCAL publisher (REI's tf_static, the stack's action status) keeps its last
    sample in a Zenoh advanced-publisher cache under ``<key>/@adv/...``, which late
    subscribers query and whose liveliness they watch: those keys go with the topic (``@adv``
    is a hermetic chunk, so ``<key>/**`` would not include them)."""
    rules = access_rules(domain, namespace, distro)
    sim, robot = rules["simulation"], rules["robot"]
    e = endpoints(domain, namespace, distro)
    # the cache answers on <key>/@adv/... with the samples' own key
    tf_static = (e["tf_static"].keyexpr, f"{e['tf_static'].keyexpr}/@adv/**")
    status = (e["status"].keyexpr, f"{e['status'].keyexpr}/@adv/**")
    added = (
        ("simulation", "publish", sim.put), ("simulation", "subscribe", sim.subscribe),
        ("simulation", "query", (*sim.query, *status)), ("simulation", "answer", tf_static),
        ("simulation", "liveliness", (sim.liveliness, tf_static[1], status[1])),
        ("robot", "publish", robot.put), ("robot", "subscribe", robot.subscribe),
        ("robot", "answer", (*robot.reply, *status)), ("robot", "query", tf_static),
        ("robot", "liveliness", (robot.liveliness, tf_static[1], status[1])),
    )
    for role, action, keys in added:
        access = access.with_keys(role, action, keys)
    readable = tuple(dict.fromkeys((*sim.put, *robot.put)))
    for role in ("monitor", "viewer"):
        access = access.with_keys(role, "subscribe", readable)
    return access
