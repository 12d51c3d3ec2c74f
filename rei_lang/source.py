"""Reading a user's source file defensively, before any parser sees it.

Binary junk, undecodable bytes, empty and oversized files become located diagnostics
here, so the parsers only ever receive reasonable text.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

from rei.lang.errors import Diagnostic, Span

MAX_SOURCE_BYTES = 32 * 1024 * 1024
"""Larger than any room a person or `rei-gen rooms` writes (10,000 floors is ~0.5 MiB)."""


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


def decode_source(path: str, data: bytes) -> SourceText | Diagnostic:
    if len(data) > MAX_SOURCE_BYTES:
        return Diagnostic(
            Span.point(path),
            "INPUT-SIZE",
            f"expected a file of at most {MAX_SOURCE_BYTES // (1024 * 1024)} MiB, "
            f"found {len(data) / (1024 * 1024):.1f} MiB",
        )
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


def read_source(path: str | Path) -> SourceText | Diagnostic:
    """The file's text, or one diagnostic saying why it cannot be read."""
    p = Path(path)
    shown = str(path)
    try:
        if p.is_dir():
            return Diagnostic(Span.point(shown), "INPUT-READ", "expected a file, found a folder")
        size = p.stat().st_size
        if size > MAX_SOURCE_BYTES:
            return Diagnostic(
                Span.point(shown),
                "INPUT-SIZE",
                f"expected a file of at most {MAX_SOURCE_BYTES // (1024 * 1024)} MiB, "
                f"found {size / (1024 * 1024):.1f} MiB",
            )
        data = p.read_bytes()
    except FileNotFoundError:
        return Diagnostic(Span.point(shown), "INPUT-READ", "no such file")
    except OSError as exc:
        return Diagnostic(Span.point(shown), "INPUT-READ", f"cannot read the file: {exc.strerror}")
    return decode_source(shown, data)
