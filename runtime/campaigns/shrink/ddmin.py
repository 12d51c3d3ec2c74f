"""Delta debugging (Zeller and Hildebrandt's ddmin): a 1-minimal subset that keeps a failure.

Generic over the items; the test is the caller's (here: the candidate checks clean and the
same requirement fails on every seed). This module must never know what an item is.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TypeVar

T = TypeVar("T")


def ddmin(items: Sequence[T], fails: Callable[[list[T]], bool]) -> list[T]:
    """A subset of ``items`` (in their order) on which ``fails`` holds and from which no single
    item can be removed with it still holding (1-minimal), assuming it holds on all of
    ``items``. The empty subset is tried first: in a shrink, often nothing at all of a kind
    matters. ``fails`` may raise to stop early; the caller keeps what it last accepted."""
    current = list(items)
    if not current:
        return current
    if fails([]):
        return []
    chunks = 2
    while len(current) >= 2:
        size = len(current) / chunks
        parts = [current[round(i * size):round((i + 1) * size)] for i in range(chunks)]
        reduced = False
        for part in parts:  # a part alone
            if part and len(part) < len(current) and fails(part):
                current, chunks, reduced = part, 2, True
                break
        if not reduced:
            for i in range(len(parts)):  # everything but one part
                rest = [x for j, p in enumerate(parts) if j != i for x in p]
                if len(rest) < len(current) and fails(rest):
                    current, chunks, reduced = rest, max(chunks - 1, 2), True
                    break
        if not reduced:
            if chunks >= len(current):
                break
            chunks = min(chunks * 2, len(current))
    return current  # [] was the first test: a single item left is 1-minimal already
