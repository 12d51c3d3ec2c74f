"""One .mission file analysed end to end, with the room it imports."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from rei.lang.errors import Diagnostic, sorted_diagnostics
from rei.lang.mission.linker import link_mission, room_path_of
from rei.lang.mission.model import Mission
from rei.lang.parsing import parse
from rei.lang.room.document import RoomDocument
from rei.lang.source import SourceText


@dataclass(frozen=True)
class MissionDocument:
    source: SourceText | None
    mission: Mission | None
    room: RoomDocument | None
    diagnostics: tuple[Diagnostic, ...]

    @property
    def ok(self) -> bool:
        return not any(d.is_error for d in self.diagnostics)


def analyse_mission(source: SourceText | Diagnostic,
                    room_loader: Callable[[str], RoomDocument]) -> MissionDocument:
    """``room_loader`` maps a room path to its document (a workspace caches them)."""
    if isinstance(source, Diagnostic):
        return MissionDocument(None, None, None, (source,))
    parsed = parse("mission", source)
    if isinstance(parsed, Diagnostic):
        return MissionDocument(source, None, None, (parsed,))
    room_doc = room_loader(room_path_of(parsed, source))
    mission, diagnostics = link_mission(parsed, source, room_doc)
    return MissionDocument(source, mission, room_doc, tuple(sorted_diagnostics(diagnostics)))
