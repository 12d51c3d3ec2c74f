"""Between REI spans (lines and columns from 1, counted in characters) and LSP positions.

LSP counts lines from 0 and columns in the code units the client negotiated (UTF-16 unless
it asked for another), so a line with an accent or an emoji must be measured, never
assumed. This module must never raise on a position outside the text: editors send them
while a file is being typed.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from lsprotocol import types

from rei.lang.errors import Span

Units = Callable[[str], int]


def utf16_units(text: str) -> int:
    return len(text.encode("utf-16-le", "surrogatepass")) // 2


def utf8_units(text: str) -> int:
    return len(text.encode("utf-8", "surrogatepass"))


def utf32_units(text: str) -> int:
    return len(text)


def units_for(encoding: str | None) -> Units:
    """The code-unit counter of a negotiated position encoding (UTF-16 by default)."""
    if encoding == types.PositionEncodingKind.Utf8:
        return utf8_units
    if encoding == types.PositionEncodingKind.Utf32:
        return utf32_units
    return utf16_units


@dataclass(frozen=True)
class LineIndex:
    """The lines of one document text, as REI counts them (split on newline only)."""

    lines: tuple[str, ...]
    units: Units
    bom: bool
    """REI drops a leading byte-order mark before parsing: columns of line 1 shift by one."""

    @staticmethod
    def of(text: str, units: Units = utf16_units) -> LineIndex:
        return LineIndex(tuple(text.split("\n")), units, text.startswith("\ufeff"))

    def position(self, line: int, col: int) -> types.Position:
        """The LSP position of a 1-based REI line and column, clamped into the text."""
        if line < 1:
            return types.Position(line=0, character=0)
        if line > len(self.lines):
            last = len(self.lines) - 1
            return types.Position(line=last, character=self.units(self.lines[last]))
        text = self.lines[line - 1]
        chars = max(col - 1, 0) + (1 if self.bom and line == 1 else 0)
        return types.Position(line=line - 1, character=self.units(text[:chars]))

    def range(self, span: Span) -> types.Range:
        start = self.position(span.line, span.col)
        end = self.position(span.end_line, span.end_col)
        if (end.line, end.character) < (start.line, start.character):
            end = start
        return types.Range(start=start, end=end)

    def rei_position(self, position: types.Position) -> tuple[int, int]:
        """The 1-based REI line and column of an LSP position, clamped into the text."""
        if position.line >= len(self.lines):
            return len(self.lines), len(self.lines[-1]) + 1
        line = max(position.line, 0)
        text = self.lines[line]
        chars = 0
        used = 0
        for char in text:
            if used >= position.character:
                break
            used += self.units(char)
            chars += 1
        if self.bom and line == 0:
            chars = max(chars - 1, 0)
        return line + 1, chars + 1

    def line_text(self, line: int) -> str:
        """The text of a 1-based REI line ('' outside the file), without a byte-order mark."""
        if not 1 <= line <= len(self.lines):
            return ""
        text = self.lines[line - 1]
        return text[1:] if self.bom and line == 1 else text


def contains(span: Span, line: int, col: int) -> bool:
    """Whether a cursor at (line, col) touches the span (its end included: the cursor after
    the last character of a name is still on it)."""
    return (span.line, span.col) <= (line, col) <= (span.end_line, span.end_col)
