"""Checking and loading REI files by kind, with the rooms missions import read once.

``Workspace`` is the one entry point the command line, the language server and the
generators share, so every rule exists once. A workspace can be given file texts that are
not saved yet (an editor's buffers); otherwise it reads the disk.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from rei.lang.errors import Diagnostic, LanguageError, Span
from rei.lang.mission.document import MissionDocument, analyse_mission
from rei.lang.room.document import RoomDocument, analyse_room
from rei.lang.source import SourceText, decode_source, read_source

Document = RoomDocument | MissionDocument


def _key(path: str | Path) -> str:
    """The path with symbolic links resolved, as far as they resolve (a loop of links or an
    unreadable folder keeps the absolute path: reading it then says what is wrong)."""
    try:
        return str(Path(path).resolve())
    except (OSError, RuntimeError, ValueError):
        return os.path.abspath(path)


@dataclass
class Workspace:
    """Documents by path. Not thread-safe; one per editor session or command."""

    overlays: dict[str, str] = field(default_factory=dict)
    """Unsaved texts by resolved path; they win over the disk."""
    _rooms: dict[str, RoomDocument] = field(default_factory=dict)
    _extra_kinds: dict[str, Callable[[SourceText | Diagnostic], object]] = field(
        default_factory=dict)

    def set_text(self, path: str | Path, text: str) -> None:
        self.overlays[_key(path)] = text
        self._rooms.clear()

    def forget_text(self, path: str | Path) -> None:
        self.overlays.pop(_key(path), None)
        self._rooms.clear()

    def invalidate(self) -> None:
        self._rooms.clear()

    def source(self, path: str | Path) -> SourceText | Diagnostic:
        overlay = self.overlays.get(_key(path))
        if overlay is not None:
            return decode_source(str(path), overlay.encode("utf-8"))
        return read_source(path)

    def room(self, path: str | Path) -> RoomDocument:
        key = _key(path)
        if key not in self._rooms:
            self._rooms[key] = analyse_room(self.source(path))
        return self._rooms[key]

    def mission(self, path: str | Path) -> MissionDocument:
        return analyse_mission(self.source(path), self._imported_room)

    def _imported_room(self, path: str | Path) -> RoomDocument:
        """The room a mission imports; a file that is not a .room is never read (its text
        would be parsed as a room and echoed in the syntax error)."""
        if path and Path(path).suffix != ".room":
            name = Path(path).name
            return analyse_room(Diagnostic(
                Span.point(str(path)), "INPUT-KIND",
                f"expected a .room file, found '{name}'"))
        return self.room(path)

    def check(self, path: str | Path) -> list[Diagnostic]:
        """Every diagnostic of one file (for a mission, problems of its room are summarised)."""
        suffix = Path(path).suffix
        if suffix == ".room":
            return list(self.room(path).diagnostics)
        if suffix == ".mission":
            return list(self.mission(path).diagnostics)
        if suffix == ".toml":
            return self.check_catalogue(path)
        checker = _extra_checkers().get(suffix)
        if checker is not None:
            return checker(self, path)
        return [Diagnostic(Span.point(str(path)), "INPUT-KIND",
                           f"expected a file ending in {', '.join(sorted(known_suffixes()))}, "
                           f"found '{suffix or Path(path).name}'")]


    def check_catalogue(self, path: str | Path) -> list[Diagnostic]:
        """Problems of a catalogue file (TOML) given on its own."""
        from rei.catalogue import CatalogueError, load_catalogue

        try:
            load_catalogue(path)
        except CatalogueError as exc:
            return list(exc.diagnostics)
        return []


Checker = Callable[[Workspace, "str | Path"], list[Diagnostic]]


def _extra_checkers() -> dict[str, Checker]:
    """Checkers of languages that live in other modules (.vepl), imported on demand."""
    checkers: dict[str, Checker] = {}
    try:
        from rei.lang.vepl.document import check_vepl
    except ImportError:
        return checkers
    checkers[".vepl"] = check_vepl
    return checkers


def known_suffixes() -> set[str]:
    return {".room", ".mission", ".toml", *_extra_checkers()}


def load_room(path: str | Path, workspace: Workspace | None = None) -> RoomDocument:
    """A valid room document; raises LanguageError with every problem otherwise."""
    doc = (workspace or Workspace()).room(path)
    if not doc.ok or doc.room is None:
        raise LanguageError([d for d in doc.diagnostics if d.is_error])
    return doc


def load_mission(path: str | Path, workspace: Workspace | None = None) -> MissionDocument:
    """A valid mission document (with its valid room); raises LanguageError otherwise."""
    doc = (workspace or Workspace()).mission(path)
    if not doc.ok or doc.mission is None:
        raise LanguageError([d for d in doc.diagnostics if d.is_error])
    return doc
