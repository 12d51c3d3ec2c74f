"""Reading a user's source file defensively, before any parser sees it.

Every file REI reads as input (.room, .mission, .vepl, imported rooms, catalogue TOML) comes
through ``read_source``: only regular files are read (a FIFO, a device or a folder is named,
never opened for reading, so nothing blocks), and at most ``MAX_SOURCE_BYTES + 1`` bytes are
read whatever ``stat`` says (``/proc`` files and growing files lie about their size). Binary
junk, undecodable bytes, empty and oversized files become located diagnostics here, so the
parsers only ever receive reasonable text. This module must never block or read unboundedly.
"""

from __future__ import annotations

import bisect
import errno
import hashlib
import os
import stat
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

from rei.lang.errors import Diagnostic, Span

MAX_SOURCE_BYTES = 32 * 1024 * 1024
"""Larger than any room a person or `rei-gen rooms` writes (10,000 floors is ~0.5 MiB)."""

_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
          (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
          (stat.S_ISSOCK, "a socket"))


@dataclass(frozen=True)
class SourceText:
    path: str
    text: str

    @cached_property
    def _line_starts(self) -> list[int]:
        starts = [0]
        find = self.text.find
        pos = find("\n")
        while pos >= 0:
            starts.append(pos + 1)
            pos = find("\n", pos + 1)
        return starts

    def line_col(self, offset: int) -> tuple[int, int]:
        """1-based line and column of a character offset (O(log lines))."""
        index = bisect.bisect_right(self._line_starts, offset) - 1
        return index + 1, offset - self._line_starts[index] + 1


def line_col(text: str, offset: int) -> tuple[int, int]:
    """1-based line and column of a character offset."""
    line = text.count("\n", 0, offset) + 1
    col = offset - (text.rfind("\n", 0, offset) + 1) + 1
    return line, col


def _too_big(path: str, size: int) -> Diagnostic:
    shown = (f"{size / (1024 * 1024):.1f} MiB" if size > MAX_SOURCE_BYTES + 1
             else "more than that")
    return Diagnostic(Span.point(path), "INPUT-SIZE",
                      f"expected a file of at most {MAX_SOURCE_BYTES // (1024 * 1024)} MiB, "
                      f"found {shown}")


def decode_source(path: str, data: bytes) -> SourceText | Diagnostic:
    if len(data) > MAX_SOURCE_BYTES:
        return _too_big(path, len(data))
    nul = data.find(b"\x00")
    if nul >= 0:
        line, col = line_col(data[:nul].decode("utf-8", "replace"), nul)
        return Diagnostic(
            Span.point(path, line, col),
            "INPUT-ENCODING",
            "expected UTF-8 text, found a NUL byte (is this a binary file?)",
        )
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        prefix = data[: exc.start].decode("utf-8", "replace")
        line, col = line_col(prefix, len(prefix))
        return Diagnostic(
            Span.point(path, line, col),
            "INPUT-ENCODING",
            f"expected UTF-8 text, found the byte 0x{data[exc.start]:02x}",
        )
    text = text.removeprefix("\ufeff")
    if not text.strip():
        return Diagnostic(Span.point(path), "INPUT-EMPTY", "expected a model, found an empty file")
    return SourceText(path, text)


def file_kind(mode: int) -> str | None:
    """What a non-regular file is ("a FIFO (named pipe)", ...); None for a regular file."""
    if stat.S_ISREG(mode):
        return None
    return next((name for test, name in _KINDS if test(mode)), "not a regular file")


Reads = list[tuple[str, str | None]]
_READS: ContextVar[Reads | None] = ContextVar("rei_source_reads", default=None)


@contextmanager
def recorded_reads() -> Iterator[Reads]:
    """Every file ``read_bounded`` is asked for while the block runs, in order: (absolute
    path, sha256 of the bytes read, or None when it could not be read). The inputs a result
    was made from, by which a cache of generated artifacts (rei.runtime.runs.cache) knows when
    that result is stale."""
    reads: Reads = []
    token = _READS.set(reads)
    try:
        yield reads
    finally:
        _READS.reset(token)


def read_bounded(path: str | Path, limit: int = MAX_SOURCE_BYTES) -> bytes | Diagnostic:
    """At most ``limit + 1`` bytes of a regular file, or one diagnostic saying why not
    (``_read_bounded``); noted for ``recorded_reads``."""
    data = _read_bounded(path, limit)
    reads = _READS.get()
    if reads is not None:
        digest = hashlib.sha256(data).hexdigest() if isinstance(data, bytes) else None
        reads.append((os.path.abspath(path) if str(path) else "", digest))
    return data


def unreadable(path: str | Path) -> Diagnostic | None:
    """Why ``path`` cannot be read as a source file (one INPUT-READ diagnostic: no name, no
    such file, not a regular file, a loop of links, ...), or None when it is a regular file.
    Looks only (``stat``): what a command checks before it starts work on a file it will read
    later, with the words the file's reader would use."""
    shown = str(path)
    if shown == "":
        return Diagnostic(Span.point(shown), "INPUT-READ",
                          "expected a file name, found an empty string")
    try:
        kind = file_kind(os.stat(path).st_mode)
    except (OSError, ValueError) as exc:
        return _not_read(shown, exc)
    if kind is not None:
        return Diagnostic(Span.point(shown), "INPUT-READ", f"expected a regular file, found {kind}")
    return None


def _not_read(shown: str, exc: OSError | ValueError) -> Diagnostic:
    if isinstance(exc, FileNotFoundError):
        return Diagnostic(Span.point(shown), "INPUT-READ", "no such file")
    if isinstance(exc, OSError):
        if exc.errno == errno.ELOOP:
            return Diagnostic(Span.point(shown), "INPUT-READ",
                              "expected a file, found a loop of symbolic links")
        return Diagnostic(Span.point(shown), "INPUT-READ",
                          f"cannot read the file: {exc.strerror or exc}")
    return Diagnostic(Span.point(shown), "INPUT-READ", f"cannot read the file: {exc}")  # NUL


def _read_bounded(path: str | Path, limit: int = MAX_SOURCE_BYTES) -> bytes | Diagnostic:
    """At most ``limit + 1`` bytes of a regular file, or one diagnostic saying why not.

    The file is checked with ``stat`` before it is opened (``unreadable``: a FIFO would block
    ``open``), opened with O_NONBLOCK (in case it was swapped for a FIFO in between) and
    checked again through the open descriptor; the read stops after ``limit + 1`` bytes
    whatever the size ``stat`` reported.
    """
    problem = unreadable(path)
    if problem is not None:
        return problem
    shown = str(path)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
        try:
            info = os.fstat(fd)
            kind = file_kind(info.st_mode)
            if kind is not None:
                return Diagnostic(Span.point(shown), "INPUT-READ",
                                  f"expected a regular file, found {kind}")
            if info.st_size > limit:
                return _too_big(shown, info.st_size)
            chunks: list[bytes] = []
            left = limit + 1
            while left > 0:
                chunk = os.read(fd, min(left, 1 << 20))
                if not chunk:
                    break
                chunks.append(chunk)
                left -= len(chunk)
            return b"".join(chunks)
        finally:
            os.close(fd)
    except (OSError, ValueError) as exc:  # gone or changed since it was looked at
        return _not_read(shown, exc)


def repeated_key(pairs: list[tuple[str, object]]) -> tuple[str, int] | None:
    """The first key a JSON object names more than once, and how often (None: each once).
    JSON readers keep the last value of a repeated key, so a repeated field can hide one."""
    keys = [k for k, _ in pairs]
    if len(set(keys)) == len(keys):
        return None
    first = next(k for k in keys if keys.count(k) > 1)
    return first, keys.count(first)


class UnreadableInput(Exception):
    """A small input file (an index, a run configuration) that cannot be read as text;
    ``str(error)`` says why, without the file's name (the caller names it)."""


def bounded_text(path: str | Path, limit: int = MAX_SOURCE_BYTES) -> str:
    """The UTF-8 text of a regular file of at most ``limit`` bytes, read as ``read_bounded``
    reads (never blocking on a FIFO, never reading /dev/zero without end)."""
    raw = read_bounded(path, limit)
    if isinstance(raw, Diagnostic):
        raise UnreadableInput(raw.message)
    if len(raw) > limit:
        raise UnreadableInput(f"expected at most {limit} bytes, found more")
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise UnreadableInput(f"expected UTF-8 text, found the bytes "
                              f"{raw[exc.start:exc.start + 8]!r} at byte {exc.start}") from None


def read_source(path: str | Path) -> SourceText | Diagnostic:
    """The file's text, or one diagnostic saying why it cannot be read."""
    data = read_bounded(path)
    if isinstance(data, Diagnostic):
        return data
    return decode_source(str(path), data)
