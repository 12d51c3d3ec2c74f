"""Stopping a check whose text is already stale, on the one thread that checks.

A check runs on the server's checker thread (the ``Workspace`` is not thread-safe); a 150 kB
.vepl takes tens of seconds to parse, and an edit meanwhile used to wait for the stale check
to finish. ``StaleCheck`` is raised *inside* the checker thread (CPython's
``PyThreadState_SetAsyncExc``) while, and only while, that document's check is running: the
lock below makes "is it still running" and "raise in it" one step, and the check's own
wrapper disarms under the same lock before it returns, so the exception can never land in
another job. The exception is a ``BaseException``: the checker's "any bug is an INTERNAL
diagnostic" handler (``except Exception``) must not take a cancellation for a bug.

This module must never cancel anything but a check (never a set_text or other job whose
half-done state would matter): only ``run`` arms it.
"""

from __future__ import annotations

import ctypes
import threading
from collections.abc import Callable
from typing import Any, TypeVar

R = TypeVar("R")


class StaleCheck(BaseException):
    """Raised in the checker thread: newer text of the document arrived."""


def _checkpoint() -> None:
    """An empty call: CPython delivers a pending asynchronous exception on entering a
    function, so one raised just before disarming lands here, inside ``run``'s handler."""


class CheckCanceller:
    """Arms around one check at a time; ``cancel`` raises StaleCheck in it if it runs."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._armed: str | None = None
        self._thread: int | None = None
        self._generation: dict[str, int] = {}
        self.cancelled = 0
        """How many checks were stopped (for logs and tests)."""

    def generation(self, key: str) -> int:
        """Taken when a check is submitted: a cancel after it makes the check stale."""
        with self._lock:
            return self._generation.get(key, 0)

    def run(self, key: str, generation: int, fn: Callable[..., R], *args: Any) -> R | None:
        """On the checker thread: ``fn(*args)``, or None when it was cancelled (before it
        started, or while it ran)."""
        try:
            try:
                with self._lock:
                    if self._generation.get(key, 0) != generation:
                        self.cancelled += 1
                        return None  # cancelled while it waited in the queue
                    self._armed = key
                    self._thread = threading.get_ident()
                return fn(*args)
            finally:
                with self._lock:
                    self._armed = None
                _checkpoint()
        except StaleCheck:
            return None

    def cancel(self, key: str) -> bool:
        """From any thread: stop the check of ``key`` that runs or waits; False when none
        was running (a waiting one is skipped all the same)."""
        with self._lock:
            self._generation[key] = self._generation.get(key, 0) + 1
            if self._armed != key or self._thread is None:
                return False
            self._armed = None  # one exception per check, never a second one later
            done = ctypes.pythonapi.PyThreadState_SetAsyncExc(
                ctypes.c_ulong(self._thread), ctypes.py_object(StaleCheck))
            self.cancelled += int(done == 1)
            return bool(done == 1)

    def forget(self, key: str) -> None:
        with self._lock:
            self._generation.pop(key, None)
