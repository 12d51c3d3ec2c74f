"""REI spans ⇄ LSP positions: code units of the negotiated encoding, clamping, byte-order mark."""

from __future__ import annotations

from lsprotocol import types

from rei.lang.errors import Span
from rei.lang.lsp.positions import LineIndex, units_for, utf8_units, utf16_units, utf32_units

TEXT = "room r {\n    // café 😀 here\n    floor a\n}\n"


def test_columns_are_counted_in_the_negotiated_code_units() -> None:
    # 'here' is column 20 in characters: after 'é' (1 char) and '😀' (1 char, 2 UTF-16 units,
    # 4 UTF-8 bytes).
    line = TEXT.split("\n")[1]
    col = line.index("here") + 1
    span = Span("x.room", 2, col, 2, col + 4)
    expected = {utf32_units: col - 1, utf16_units: col - 1 + 1, utf8_units: col - 1 + 1 + 3}
    for units, start in expected.items():
        index = LineIndex.of(TEXT, units)
        assert index.range(span) == types.Range(
            start=types.Position(line=1, character=start),
            end=types.Position(line=1, character=start + 4))
        assert index.rei_position(types.Position(line=1, character=start)) == (2, col)


def test_encoding_names_select_the_counter() -> None:
    assert units_for(types.PositionEncodingKind.Utf8) is utf8_units
    assert units_for(types.PositionEncodingKind.Utf32) is utf32_units
    assert units_for(types.PositionEncodingKind.Utf16) is utf16_units
    assert units_for(None) is utf16_units


def test_positions_outside_the_text_are_clamped() -> None:
    index = LineIndex.of(TEXT)
    assert index.position(0, 0) == types.Position(line=0, character=0)
    assert index.position(99, 5) == types.Position(line=4, character=0)
    assert index.position(1, 500) == types.Position(line=0, character=len("room r {"))
    assert index.rei_position(types.Position(line=1000, character=3)) == (5, 1)
    assert index.rei_position(types.Position(line=0, character=1000)) == (1, len("room r {") + 1)
    backwards = Span("x.room", 3, 9, 3, 2)
    assert index.range(backwards).end == index.range(backwards).start


def test_a_byte_order_mark_shifts_the_first_line_only() -> None:
    # REI drops the mark before parsing, so its column 1 is the editor's character 1.
    index = LineIndex.of("\ufeff" + TEXT)
    assert index.position(1, 1) == types.Position(line=0, character=1)
    assert index.position(2, 1) == types.Position(line=1, character=0)
    assert index.rei_position(types.Position(line=0, character=1)) == (1, 1)
    assert index.line_text(1) == "room r {"
