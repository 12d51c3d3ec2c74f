"""Who may do what on the bus: the roles, their key-expression lists, and the router's rules.

Each role (``ROLES``) has, per action (``ACTIONS``), the key expressions it may act on.
``AccessRules.router_acl`` turns them into Zenoh's ``access_control`` section, which the
router enforces whatever a client does (default: deny); ``RoleAccess.allows`` is the same
rule on the client's side, so a component about to do what its role may not says so in one
line instead of being silently ignored by the router. The lists are data: another profile
(the ROS 2 keys of rmw_zenoh for the robot role) adds its keys with ``with_keys`` before
``rei bus`` writes the router's configuration. This module must never open a session.

What each action means at the router (Zenoh's message kinds and flows, seen from it):

* publish: ``put`` and ``delete`` coming in (and, for every role that publishes or asks,
  the declarations of subscribers and answerers going out, so a publisher knows whether
  anyone reads it);
* subscribe: ``declare_subscriber`` coming in, ``put`` and ``delete`` going out;
* query: ``query`` coming in, ``reply`` going out (asking for configuration, calling the
  robot);
* answer: ``declare_queryable`` and ``reply`` coming in, ``query`` going out;
* liveliness: tokens declared and watched (the ROS 2 profile's graph discovery).
"""

from __future__ import annotations

import fnmatch
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, replace
from typing import Any, Literal, get_args

from rei.runtime.bus.errors import BusError
from rei.runtime.bus.schema import ALL, CONFIG, PREFIX, TRACE

Role = Literal["simulation", "robot", "monitor", "viewer", "mission"]
ROLES: tuple[str, ...] = get_args(Role)
Action = Literal["publish", "subscribe", "query", "answer", "liveliness"]
ACTIONS: tuple[str, ...] = get_args(Action)

_ZENOH: dict[str, tuple[tuple[str, tuple[str, ...]], ...]] = {
    "publish": (("ingress", ("put", "delete")),),
    "subscribe": (("ingress", ("declare_subscriber",)), ("egress", ("put", "delete"))),
    "query": (("ingress", ("query",)), ("egress", ("reply",))),
    "answer": (("ingress", ("declare_queryable", "reply")), ("egress", ("query",))),
    "liveliness": (("ingress", ("liveliness_token", "declare_liveliness_subscriber",
                                "liveliness_query")),
                   ("egress", ("liveliness_token", "liveliness_query"))),
}
"""Action -> (flow, Zenoh message kinds) the router must allow for it."""

ROBOT_CALL = f"{PREFIX}/robot/call"
"""The robot contract's requests: ``ROBOT_CALL/<op>`` (``rei.runtime.bus.remote_robot``)."""


def key_includes(pattern: str, key: str) -> bool:
    """Whether the key expression ``pattern`` includes ``key`` (``*`` one chunk, ``**`` any
    number of chunks), as Zenoh decides it for keys without wildcards of their own; a
    ``key`` with wildcards is included only by a pattern that includes every key it can
    name (checked chunk by chunk, ``**`` in ``key`` only under ``**`` in ``pattern``)."""
    return _includes(pattern.split("/"), key.split("/"))


def _includes(p: list[str], k: list[str]) -> bool:
    if not p:
        return not k
    if p[0] == "**":
        return any(_includes(p[1:], k[i:]) for i in range(len(k) + 1))
    if not k or k[0] == "**":
        return False
    if p[0] != "*" and not (k[0] != "*" and fnmatch.fnmatchcase(k[0], p[0])):
        return False
    return _includes(p[1:], k[1:])


@dataclass(frozen=True)
class RoleAccess:
    """The key expressions one role may act on, per action."""

    role: str
    keys: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    """Action -> key expressions (absent: none)."""

    def allows(self, action: str, key: str) -> bool:
        return any(key_includes(p, key) for p in self.keys.get(action, ()))

    def check(self, action: str, key: str) -> None:
        """``BusError`` in one line when the role may not ``action`` on ``key``."""
        if not self.allows(action, key):
            allowed = ", ".join(self.keys.get(action, ())) or "nothing"
            raise BusError(f"the {self.role} role may not {action} on {key} "
                           f"(it may {action} on: {allowed})")


@dataclass(frozen=True)
class AccessRules:
    """Every role's access: what ``rei bus`` tells its router to enforce."""

    roles: tuple[RoleAccess, ...]
    declared: tuple[str, ...] = ()
    """Key expressions besides the schema's whose declarations every role may see (a
    profile's own keys, such as the ROS 2 profile's)."""

    def role(self, name: str) -> RoleAccess:
        for access in self.roles:
            if access.role == name:
                return access
        raise BusError(f"a role expected to be one of {', '.join(r.role for r in self.roles)}, "
                       f"found {name!r}")

    def with_keys(self, role: str, action: str, keys: Iterable[str]) -> AccessRules:
        """These rules with ``keys`` added to what ``role`` may ``action`` on (a profile's
        own keys: the ROS 2 topics of rmw_zenoh for the robot role, for instance)."""
        if action not in ACTIONS:
            raise BusError(f"an action expected to be one of {', '.join(ACTIONS)}, "
                           f"found {action!r}")
        old = self.role(role)
        merged = dict(old.keys)
        merged[action] = tuple(dict.fromkeys((*merged.get(action, ()), *keys)))
        return replace(self, roles=tuple(replace(r, keys=merged) if r is old else r
                                         for r in self.roles),
                       declared=tuple(dict.fromkeys((*self.declared, *keys))))

    def router_acl(self, users: Mapping[str, str]) -> dict[str, Any]:
        """Zenoh's ``access_control`` section: deny by default, allow per role what its
        lists name; ``users`` maps each role to the user name its credentials carry."""
        rules: list[dict[str, Any]] = []
        subjects: list[dict[str, Any]] = []
        policies: list[dict[str, Any]] = []
        for access in self.roles:
            ids = []
            for action in ACTIONS:
                keys = access.keys.get(action, ())
                if not keys:
                    continue
                for flow, messages in _ZENOH[action]:
                    rule_id = f"{access.role}-{action}-{flow}"
                    rules.append({"id": rule_id, "permission": "allow", "flows": [flow],
                                  "messages": list(messages), "key_exprs": list(keys)})
                    ids.append(rule_id)
            if any(access.keys.get(a) for a in ("publish", "query")):
                # Who reads or answers (declarations, never data): a publisher waits for
                # its readers with them. Their keys may be wider than the role's own (a
                # viewer reads rei/v1/**), so they pass on the whole schema.
                rule_id = f"{access.role}-declarations-egress"
                rules.append({"id": rule_id, "permission": "allow", "flows": ["egress"],
                              "messages": ["declare_subscriber", "declare_queryable"],
                              "key_exprs": [ALL, *self.declared]})
                ids.append(rule_id)
            subjects.append({"id": access.role, "usernames": [users[access.role]]})
            if ids:
                policies.append({"id": f"{access.role}-policy", "rules": ids,
                                 "subjects": [access.role]})
        return {"enabled": True, "default_permission": "deny", "rules": rules,
                "subjects": subjects, "policies": policies}


def _topics(*topics: str) -> tuple[str, ...]:
    return tuple(f"{PREFIX}/{t}" for t in topics)


DEFAULT_ACCESS = AccessRules((
    # The world, its sensors and the loop's records; it answers configuration and calls the
    # robot's reset/step/feedback (lock-step: one call per control period).
    RoleAccess("simulation", {
        "publish": (*_topics("truth/**", "animator/**", "sensor/**", "robot/view",
                             "robot/command"), TRACE),
        "subscribe": _topics("monitor/**"),
        "answer": (f"{CONFIG}/**",),
        "query": tuple(f"{ROBOT_CALL}/{op}" for op in ("load", "reset", "step", "feedback",
                                                                "close")),
    }),
    # Only what its sensors measured (never ground truth); it answers the calls (its
    # commands and its goal feedback are the answers) and publishes its own streams.
    RoleAccess("robot", {
        "publish": _topics("robot/out/**"),
        "subscribe": _topics("robot/view", "mission/status"),
        "answer": (f"{ROBOT_CALL}/**",),
        "query": (f"{CONFIG}/robot",),
    }),
    # Reads everything, publishes its signals.
    RoleAccess("monitor", {
        "publish": _topics("monitor/**"),
        "subscribe": (ALL,),
        "query": (f"{CONFIG}/**",),
    }),
    # Reads only.
    RoleAccess("viewer", {
        "subscribe": (ALL,),
        "query": (f"{CONFIG}/**",),
    }),
    # The mission executor: the only one that sends goals (and cancels them).
    RoleAccess("mission", {
        "publish": _topics("mission/**"),
        "subscribe": (ALL,),
        "query": (*(f"{ROBOT_CALL}/{op}" for op in ("send_goal", "cancel_goal")),
                  f"{CONFIG}/**"),
    }),
))
"""REI's own roles and keys (wire schema v1)."""
