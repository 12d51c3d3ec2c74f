"""Error types and located diagnostics shared by every REI stage.

The exception tree (one root, one subclass per stage)::

    ReiError
    ├── LanguageError      a .room / .mission / .vepl / catalogue file is not valid
    ├── GenerationError    an artifact could not be generated or written   (rei.generators)
    └── RunError           a simulation run could not be set up            (rei.runtime)

A failed test verdict is data, never an exception. Diagnostics are records, not
exceptions: a checker collects all of them and the caller decides what to do.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from enum import StrEnum

_UNPRINTABLE = re.compile("[\x00-\x1f\x7f-\x9f\u061c\u200e\u200f\u202a-\u202e"
                          "\u2066-\u2069\u2028\u2029]")
"""C0 and C1 controls (ESC starts a terminal's escape sequences), DEL, and the invisible
direction marks and overrides that make a terminal or an editor show text out of order."""


def printable(text: str) -> str:
    """``text`` with every control character written as an escape (``\\x1b``, ``\\u202e``):
    what a user's file contains is shown, never interpreted by the terminal or the editor."""
    return _UNPRINTABLE.sub(
        lambda m: f"\\x{ord(m.group(0)):02x}" if ord(m.group(0)) < 0x100
        else f"\\u{ord(m.group(0)):04x}", text)


def printable_lines(text: str) -> str:
    """``printable`` line by line: the line breaks of a message stay line breaks."""
    return "\n".join(map(printable, text.split("\n")))


class Severity(StrEnum):
    ERROR = "error"
    WARNING = "warning"


@dataclass(frozen=True, order=True)
class Span:
    """A region of a source file; lines and columns count from 1."""

    file: str
    line: int
    col: int
    end_line: int
    end_col: int

    @staticmethod
    def point(file: str, line: int = 1, col: int = 1) -> Span:
        return Span(file, line, col, line, col)


@dataclass(frozen=True)
class Diagnostic:
    """One problem found in a file: where, which rule, and what was expected vs found."""

    span: Span
    rule: str
    message: str
    severity: Severity = Severity.ERROR

    def __post_init__(self) -> None:
        # Messages quote the input (tokens, names, paths): every place that shows one (the
        # command line, JSON, the editor) gets it with its control characters escaped.
        object.__setattr__(self, "message", printable(self.message))

    def __str__(self) -> str:
        prefix = "" if self.severity is Severity.ERROR else "warning: "
        where = f"{printable(self.span.file)}:{self.span.line}:{self.span.col}"
        return f"{where}: {self.rule}: {prefix}{self.message}"

    @property
    def is_error(self) -> bool:
        return self.severity is Severity.ERROR


class ReiError(Exception):
    """Root of every error REI raises on purpose."""


class LanguageError(ReiError):
    """A source file could not be turned into a valid model; carries every diagnostic."""

    def __init__(self, diagnostics: list[Diagnostic]) -> None:
        self.diagnostics = diagnostics
        super().__init__("\n".join(str(d) for d in diagnostics) or "invalid input")


def sorted_diagnostics(diagnostics: list[Diagnostic]) -> list[Diagnostic]:
    """Source order, then rule id: the order a reader walks the file in."""
    return sorted(diagnostics, key=lambda d: (d.span.file, d.span.line, d.span.col, d.rule))
