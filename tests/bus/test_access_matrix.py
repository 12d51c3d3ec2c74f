"""Every role x action x key on a real router: the router itself (Zenoh access control)
allows exactly what ``DEFAULT_ACCESS`` says and refuses the rest, whatever a client does.

Each role acts through its raw Zenoh session (so the client's own check is bypassed, as a
forged program's would be); an auditor role of this test's router (allowed everything)
watches. Ordering makes every check exact without waiting on a clock: after each attempt the
role sends a marker query the auditor answers, and messages of one session reach the router
and leave it in order, so when the marker arrives, the attempt has arrived or never will.

A client sends a put (or a query) only where it knows of a reader (or a queryable), and a
new session learns of the ones already declared a little after it opens: so each role first
waits until its marker is answered (the auditor's readers are then known), and an allowed
attempt is repeated, each time followed by its marker, until it is seen or ``ROUNDS`` have
passed (under load a route can still lag: the rounds back off, ~8 s in all). A refused
attempt is made once and must not have arrived when its marker has: repeating never makes a
refused attempt look allowed.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from rei.runtime.bus import DEFAULT_ACCESS, ROLES, AccessRules, RoleAccess, connect
from rei.runtime.bus.router import Router, start
from rei.runtime.bus.schema import ALL
from tests.bus.conftest import SAFETY

KEYS = ("truth/robot", "sensor/laser", "robot/view", "robot/command", "mission/status",
        "monitor/signal", "robot/out/cmd", "trace", "config/world", "config/robot",
        "robot/call/step", "robot/call/send_goal")
MARKER = {"simulation": "rei/v1/robot/call/load", "robot": "rei/v1/config/robot",
          "monitor": "rei/v1/config/world", "viewer": "rei/v1/config/world",
          "mission": "rei/v1/config/world"}
"""A key each role may ask (the auditor answers it)."""
SENTINEL = {"simulation": "rei/v1/monitor/signal", "robot": "rei/v1/robot/view",
            "monitor": "rei/v1/monitor/signal", "viewer": "rei/v1/monitor/signal",
            "mission": "rei/v1/monitor/signal"}
"""A key each role may read: the auditor's put there follows its put on the key tried."""
ROUNDS = 20


class Auditor:
    def __init__(self, router: Router, folder: Path) -> None:
        self.bus = connect(router.bus.endpoint, role="auditor", credentials=folder,
                           access=AUDITED)
        z = self.bus.zenoh_session
        self.lock = threading.Lock()
        self.puts: list[str] = []
        self.queries: list[str] = []
        self.marked = threading.Event()
        self.publish_on: str | None = None
        self.sentinel = ""
        z.declare_subscriber(ALL, self._put)
        self._queryable = z.declare_queryable(ALL, self._query)

    def _put(self, sample: Any) -> None:
        with self.lock:
            self.puts.append(str(sample.key_expr))

    def _query(self, query: Any) -> None:
        key = str(query.key_expr)
        with self.lock:
            self.queries.append(key)
        if key in MARKER.values():
            if self.publish_on is not None:  # one publisher: its puts arrive in order
                self.bus.zenoh_session.put(self.publish_on, b"audit")
                self.bus.zenoh_session.put(self.sentinel, b"sentinel")
            query.reply(query.key_expr, b"marker")
            self.marked.set()
        else:
            query.reply(query.key_expr, b"audit")

    def reset(self) -> None:
        with self.lock:
            self.puts.clear()
            self.queries.clear()
        self.marked.clear()
        self.publish_on = None


AUDITED = AccessRules((*DEFAULT_ACCESS.roles,
                       RoleAccess("auditor", {a: (ALL,) for a in
                                              ("publish", "subscribe", "query", "answer")})))


@pytest.fixture(scope="module")
def audited(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Router, Auditor]]:
    with start(tmp_path_factory.mktemp("audit") / "bus", access=AUDITED) as router:
        auditor = Auditor(router, router.bus.path)
        yield router, auditor
        auditor.bus.close()


def _mark(z: Any, role: str, auditor: Auditor) -> None:
    # The marker itself is a query: asked again (a bounded number of times) while the new
    # session does not yet know of the auditor's queryable; any answered marker orders.
    for _ in range(ROUNDS):
        replies = list(z.get(MARKER[role], timeout=SAFETY))
        if any(r.ok is not None for r in replies):
            break
        time.sleep(0.05)
    else:
        raise AssertionError(f"{role}'s marker was not answered")
    assert auditor.marked.wait(SAFETY)


def _attempt(z: Any, role: str, auditor: Auditor, act: Any, delivered: Any,
             rounds: int) -> bool:
    """Do ``act`` then the marker, until ``delivered()`` or ``rounds`` rounds: when the marker
    has arrived, the attempt has arrived or never will (so a refused one is seen never)."""
    for attempt in range(rounds):
        auditor.reset()
        act()
        _mark(z, role, auditor)
        if delivered():
            return True
        backoff(attempt)
    return False


def backoff(attempt: int) -> None:
    """The pause before an allowed attempt is made again: 20 ms doubling to 0.5 s, so the
    ``ROUNDS`` rounds span about 8 s (a route lagging under load, as on CI's two cores, where
    20 rounds back to back once passed in a blink and failed an allowed publish)."""
    time.sleep(min(0.5, 0.02 * 2 ** attempt))


def rounds(access: RoleAccess, action: str, key: str) -> int:
    """How often an attempt is made: an allowed one until seen (bounded), a refused one once."""
    return ROUNDS if access.allows(action, key) else 1


@pytest.mark.parametrize("role", ROLES)
def test_the_router_enforces_every_role(audited: tuple[Router, Auditor], role: str) -> None:
    router, auditor = audited
    access = DEFAULT_ACCESS.role(role)
    seen: dict[tuple[str, str], bool] = {}
    with connect(router.bus.endpoint, role=role, credentials=router.bus.path) as session:
        z = session.zenoh_session
        # Readiness: the auditor declared its subscriber before its queryable, and a session
        # learns declarations in order, so once the marker is answered the role's session
        # knows of every reader and queryable the auditor has.
        auditor.reset()
        _mark(z, role, auditor)
        for topic in KEYS:
            key = f"rei/v1/{topic}"
            # an allowed attempt is repeated until seen (bounded); a refused one is made once
            # (the readiness marker above showed the session knows of the auditor's readers)
            seen[("publish", key)] = _attempt(
                z, role, auditor, lambda key=key: z.put(key, b"forged?"),
                lambda key=key: key in auditor.puts, rounds(access, "publish", key))
            seen[("query", key)] = _attempt(
                z, role, auditor,
                lambda key=key: z.get(key, lambda reply: None, timeout=SAFETY),
                lambda key=key: key in auditor.queries, rounds(access, "query", key))
            # subscribe: when the marker reaches the auditor, it publishes on the key, then
            # on a key the role may read: once that arrives, the first has or never will
            auditor.reset()
            got: list[bytes] = []
            done = threading.Event()

            def heard(sample: Any, got: list[bytes] = got, done: threading.Event = done
                      ) -> None:
                payload = sample.payload.to_bytes()
                got.append(payload)
                if payload == b"sentinel":
                    done.set()

            subs = [z.declare_subscriber(k, heard) for k in (key, SENTINEL[role])]
            # A client sends a put only where it knows of a reader, and the router may tell
            # it of a new one a little after the marker: a refused reader is never told of,
            # an allowed one within a few rounds.
            # (a refused one gets the same rounds, back to back: the auditor had as many
            # chances to learn of a reader the router let through)
            for attempt in range(ROUNDS):
                auditor.reset()
                done.clear()
                auditor.publish_on, auditor.sentinel = key, SENTINEL[role]
                _mark(z, role, auditor)
                assert done.wait(SAFETY)
                if b"audit" in got:
                    break
                if access.allows("subscribe", key):
                    backoff(attempt)
            seen[("subscribe", key)] = b"audit" in got
            for sub in subs:
                sub.undeclare()
            # answer
            auditor.reset()
            queryable = z.declare_queryable(key, lambda q: q.reply(q.key_expr, role.encode()))
            _mark(z, role, auditor)
            # asked again while the auditor's session may not yet know of the new queryable
            # (a refused one is never asked, so never answers)
            for attempt in range(rounds(access, "answer", key)):
                answers = [r.ok.payload.to_bytes() for r in auditor.bus.zenoh_session.get(
                    key, timeout=SAFETY) if r.ok is not None]
                if role.encode() in answers:
                    break
                backoff(attempt)
            seen[("answer", key)] = role.encode() in answers
            queryable.undeclare()
    expected = {(action, key): access.allows(action, key) for action, key in seen}
    assert seen == expected
    assert any(seen.values())  # not vacuous: every role may do something
