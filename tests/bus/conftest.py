"""A real Zenoh router on loopback, shared by the bus tests of a session (each test joins it
with its own sessions and closes them)."""

from __future__ import annotations

import subprocess
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from rei.runtime.bus import BusSession, connect
from rei.runtime.bus.router import Router, start

SAFETY = 20.0
"""Wall seconds a test waits for a delivery before it fails instead of hanging (the
deliveries themselves take milliseconds; nothing here measures time)."""


@pytest.fixture(scope="session")
def router(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Router]:
    with start(tmp_path_factory.mktemp("bus") / "creds") as running:
        yield running


@pytest.fixture
def join(router: Router) -> Iterator[Any]:
    """join(role) -> a session of that role on the shared router, closed after the test."""
    sessions: list[BusSession] = []

    def _join(role: str, credentials: Path | None = None) -> BusSession:
        session = connect(router.bus.endpoint, role=role,
                          credentials=credentials or router.bus.path)
        sessions.append(session)
        return session

    yield _join
    for s in sessions:
        s.close()


class Inbox:
    """What a subscriber received, and a way to wait for the n-th item."""

    def __init__(self) -> None:
        self.items: list[Any] = []
        self._changed = threading.Condition()

    def __call__(self, *item: Any) -> None:
        with self._changed:
            self.items.append(item if len(item) > 1 else item[0])
            self._changed.notify_all()

    def wait(self, n: int) -> list[Any]:
        with self._changed:
            assert self._changed.wait_for(lambda: len(self.items) >= n, SAFETY), \
                f"{len(self.items)} of {n} deliveries arrived"
            return list(self.items)


def stop_all(processes: list[subprocess.Popen[str]]) -> None:
    """Stop what a test started (last first) and close its pipes."""
    for process in reversed(processes):
        if process.poll() is None:
            process.terminate()
            process.wait(timeout=SAFETY)
        for stream in (process.stdout, process.stderr):
            if stream is not None:
                stream.close()
