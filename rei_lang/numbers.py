"""Numbers written in REI files: parsed, and rejected at the edge when not finite or absurd."""

from __future__ import annotations

import math

from rei.lang.errors import Diagnostic, Span


def read_number(
    text: str,
    span: Span,
    what: str,
    diagnostics: list[Diagnostic],
    *,
    low: float,
    high: float,
    low_open: bool = False,
    integer: bool = False,
) -> float | None:
    """The value of a number literal, or None (with a diagnostic) when it is unusable."""
    try:
        value = float(text)
    except ValueError:  # the grammar only admits number literals; defensive
        diagnostics.append(
            Diagnostic(span, "NUM-FINITE", f"{what}: expected a number, found '{text}'"))
        return None
    if not math.isfinite(value):
        diagnostics.append(
            Diagnostic(span, "NUM-FINITE", f"{what}: expected a finite number, found '{text}'")
        )
        return None
    too_low = value <= low if low_open else value < low
    if too_low or value > high or (integer and not value.is_integer()):
        bound = f"{'>' if low_open else '>='} {low:g} and <= {high:g}"
        kind = "a whole number" if integer else "a number"
        diagnostics.append(
            Diagnostic(span, "NUM-RANGE", f"{what}: expected {kind} {bound}, found {text}")
        )
        return None
    return value


MAX_OFFSET = 50.0
"""m: the largest `offset` either way (half the largest tile); the room's own tile size
bounds it further (rei.lang.room.checks.offset_problem)."""
NO_OFFSET = (0.0, 0.0)


def read_offset(dx: str, dy: str, span: Span, what: str,
                diagnostics: list[Diagnostic]) -> tuple[float, float]:
    """An ``offset DX DY`` (metres from a floor's centre); (0, 0) with a diagnostic when a
    number is unusable, so the rest of the file is still checked."""
    x = read_number(dx, span, f"{what} (x, metres)", diagnostics, low=-MAX_OFFSET,
                    high=MAX_OFFSET)
    y = read_number(dy, span, f"{what} (y, metres)", diagnostics, low=-MAX_OFFSET,
                    high=MAX_OFFSET)
    return (x if x is not None else 0.0, y if y is not None else 0.0)
