"""One .room file analysed end to end: read, parse, link, lay out, check against the catalogue."""

from __future__ import annotations

from dataclasses import dataclass

from rei.catalogue import Catalogue, CatalogueError, load_catalogue
from rei.lang.errors import Diagnostic, sorted_diagnostics
from rei.lang.parsing import parse
from rei.lang.room.checks import check_placement, check_types
from rei.lang.room.layout import Layout, compute_layout
from rei.lang.room.linker import link_room
from rei.lang.room.model import Room
from rei.lang.room.motion import check_motion
from rei.lang.source import SourceText


@dataclass(frozen=True)
class RoomDocument:
    """Everything known about one room file; ``room`` is None only when it does not parse."""

    source: SourceText | None
    room: Room | None
    layout: Layout | None
    catalogue: Catalogue | None
    diagnostics: tuple[Diagnostic, ...]

    @property
    def ok(self) -> bool:
        return not any(d.is_error for d in self.diagnostics)


def analyse_room(source: SourceText | Diagnostic) -> RoomDocument:
    if isinstance(source, Diagnostic):
        return RoomDocument(None, None, None, None, (source,))
    parsed = parse("room", source)
    if isinstance(parsed, Diagnostic):
        return RoomDocument(source, None, None, None, (parsed,))
    room, diagnostics = link_room(parsed, source)
    layout, layout_diagnostics = compute_layout(room)
    diagnostics.extend(layout_diagnostics)
    diagnostics.extend(check_motion(room, layout.cells))
    catalogue: Catalogue | None
    try:
        catalogue = load_catalogue(room.catalogue_path)
    except CatalogueError as exc:
        catalogue = None
        assert room.catalogue_span is not None
        diagnostics.extend(exc.diagnostics)
        diagnostics.append(Diagnostic(room.catalogue_span, "CATALOGUE-FILE",
                                      f"expected a valid catalogue file, found "
                                      f"{len(exc.diagnostics)} problem(s) in "
                                      f"'{room.catalogue_path}'"))
    if catalogue is not None:
        diagnostics.extend(check_types(room, catalogue))
    diagnostics.extend(check_placement(room, layout))
    return RoomDocument(source, room, layout, catalogue, tuple(sorted_diagnostics(diagnostics)))
