"""Rename as a law over every example (issue 27.1): renaming any declared name of any
example room, mission or .vepl file to a fresh name, with the edits rei-lsp would send,
leaves every file checking clean and the old name gone (the end-to-end protocol tests are
in test_rename_references.py; this one covers every name of every shipped file)."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import pytest

from rei.lang.lsp import symbols, vepl_support
from rei.lang.workspace import Workspace, load_room
from tests.conftest import example_files

NEW = "renamed_name"


def applied(occurrences: list[symbols.Occurrence], new: str) -> dict[str, str]:
    """Each file's text with its occurrences replaced (from the end, so offsets hold)."""
    by_file: dict[str, list[symbols.Occurrence]] = {}
    for occurrence in occurrences:
        by_file.setdefault(occurrence.path, []).append(occurrence)
    out = {}
    for path, found in by_file.items():
        text = found[0].text
        for o in sorted(found, key=lambda o: (o.span.line, o.span.col), reverse=True):
            start = symbols.offset_of(text, o.span.line, o.span.col)
            end = symbols.offset_of(text, o.span.end_line, o.span.end_col)
            text = text[:start] + new + text[end:]
        out[path] = text
    return out


def errors(texts: dict[str, str], paths: list[str]) -> list[str]:
    workspace = Workspace()
    for path, text in texts.items():
        workspace.set_text(path, text)
    return [f"{d.span.file}:{d.span.line}: {d.rule} {d.message}" for path in paths
            for d in workspace.check(path) if d.is_error]


@pytest.mark.parametrize("room_path", example_files(".room"), ids=lambda p: p.name)
def test_every_room_name_renames_cleanly(room_path: Path) -> None:
    room = load_room(room_path).room
    assert room is not None
    path = str(room_path.resolve())
    missions = [str(m.resolve()) for m in example_files(".mission")
                if symbols.imported_room(str(m.resolve()), m.read_text(encoding="utf-8")) == path]
    declared = symbols.room_declared(room)
    renamed = 0
    for name in declared:
        target = symbols.room_target(room, path, name)
        assert target is not None
        if target.refused is not None:
            assert target.kind == "grid cell"
            continue
        symbols.check_new_name(target, NEW, declared)
        found = symbols.room_references(room, path, target, symbols.read_text, missions)
        assert any(o.declaration for o in found) or target.kind == "grid", name
        texts = applied(found, NEW)
        assert errors(texts, [path, *missions]) == [], name
        if target.kind != "grid":
            room_text = texts.get(path, room_path.read_text(encoding="utf-8"))
            assert name not in {t.text for _, t in symbols.room_name_tokens(
                symbols.tokens(room_text))}, name
        renamed += 1
    assert renamed >= 3


VEPL_FILES = [*example_files(".vepl"),
              Path(str(resources.files("rei.lang.vepl").joinpath("default.vepl")))]


@pytest.mark.parametrize("vepl_path", VEPL_FILES, ids=lambda p: p.name)
def test_every_vepl_name_renames_cleanly(vepl_path: Path) -> None:
    text = vepl_path.read_text(encoding="utf-8")
    path = str(vepl_path.resolve())
    spec = vepl_support.specification(vepl_support.analyse(Workspace().source(path)))
    assert spec is not None
    declared = symbols.vepl_declared(spec)
    toks = symbols.tokens(text)
    renamed = 0
    for name in declared:
        token = next(t for t in toks if t.text == name and t.name)
        target = symbols.vepl_target(spec, text, path, token)
        assert target is not None and target.name == name
        if target.refused is not None:
            assert name in symbols.RUNTIME_PARAMETERS
            continue
        symbols.check_new_name(target, NEW, declared)
        found = symbols.vepl_occurrences(target, text)
        assert sum(o.declaration for o in found) == 1, name
        texts = applied(found, NEW)
        assert errors(texts, [path]) == [], name
        assert name not in {t.text for t in symbols.tokens(texts[path])}, name
        renamed += 1
    assert renamed >= 3
