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
