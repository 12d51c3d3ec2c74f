"""Static twins of missions (``--pair-static``): the same room without its people.

Thesis 7.4 ran every mission again in its room without humans to tell whether a failure came
from the people or from the room. A twin is made from the source text, not re-printed from the
model: the declarations of humans and dynamic objects are cut out at the spans the parser
reports, so everything else (grids, comments, the catalogue, the robot) stays byte for byte the
room that was tested. The twin's mission is the original text with its room reference pointed
at the twin room. This module must never run a mission; it writes only the twin files.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from rei.generators.output import write_atomic
from rei.lang.errors import Span
from rei.lang.source import SourceText
from rei.runtime.campaigns.errors import CampaignError
from rei.runtime.campaigns.plan import CampaignPlan

REMOVED_ROLES = ("human", "dynamic")


@dataclass(frozen=True)
class StaticTwin:
    """The texts of a mission's static twin and what was taken out of its room."""

    mission_text: str
    room_name: str
    """File name of the twin room, next to the twin mission."""
    room_text: str
    removed: tuple[str, ...]


def _offset(source: SourceText, line: int, col: int) -> int:
    """The character offset of a 1-based line and column (lines end at "\\n", as in spans)."""
    start = 0
    for _ in range(line - 1):
        start = source.text.index("\n", start) + 1
    return start + col - 1


def _cut(source: SourceText, replacements: list[tuple[Span, str]]) -> str:
    """``source`` with each span replaced; spans are applied back to front (offsets hold)."""
    text = source.text
    spans = sorted(((_offset(source, s.line, s.col), _offset(source, s.end_line, s.end_col), new)
                    for s, new in replacements), reverse=True)
    for start, end, new in spans:
        text = text[:start] + new + text[end:]
    return text


def static_twin(mission_file: Path) -> StaticTwin:
    """The static twin of a valid mission; CampaignError (named file) when it does not load."""
    from rei.lang.errors import LanguageError  # noqa: PLC0415  (the language is heavy)
    from rei.lang.workspace import load_mission  # noqa: PLC0415

    try:
        doc = load_mission(mission_file)
    except LanguageError as exc:
        raise CampaignError(f"{mission_file}: cannot make its static twin: {exc}") from exc
    mission, room_doc = doc.mission, doc.room
    assert mission is not None and doc.source is not None
    assert room_doc is not None and room_doc.room is not None and room_doc.source is not None
    room = room_doc.room
    gone = [o for o in room.objects if o.role in REMOVED_ROLES]
    # Cut to nothing (a comment could swallow a declaration written on the same line).
    cuts: list[tuple[Span, str]] = [(o.span, "") for o in gone]
    if room.catalogue_span is not None and room.catalogue_path is not None:
        # The twin lives elsewhere: a relative catalogue path must keep naming the same file.
        absolute = Path(room.catalogue_path).resolve().as_posix()
        cuts.append((room.catalogue_span, f"catalogue {json.dumps(absolute)}"))
    room_name = Path(mission.room_path).name
    header = (f"// Static twin of {Path(mission.room_path).resolve().as_posix()} written by "
              f"`rei campaign --pair-static`.\n// Removed (humans and dynamic objects): "
              f"{', '.join(o.name for o in gone) or 'none'}\n")
    room_text = header + _cut(room_doc.source, cuts)
    mission_text = _cut(doc.source, [(mission.room_span, json.dumps(room_name))])
    return StaticTwin(mission_text, room_name, room_text, tuple(o.name for o in gone))


def write_static_twins(plan: CampaignPlan) -> list[Path]:
    """Write (or refresh) the twin files of every static run of ``plan``; the twin missions.

    Writing is idempotent and atomic per file, so a resumed campaign rewrites identical bytes
    and a run never reads half a file. A mission that does not load gets no twin: its twin run
    then fails like the original (no mission file), and is recorded, not raised.
    """
    by_id = {s.run_id: s for s in plan.runs}
    written: list[Path] = []
    done: set[str] = set()
    for spec in plan.runs:
        if not spec.static_pair or spec.mission_file in done:
            continue
        done.add(spec.mission_file)
        original = by_id.get(spec.pair)
        if original is None:
            raise CampaignError(f"run {spec.run_id}: its pair '{spec.pair}' is not in the plan")
        try:
            twin = static_twin(Path(original.mission_file))
        except CampaignError:
            continue
        target = Path(spec.mission_file)
        for folder in (target.parent.parent, target.parent):  # DIR/static/NAME: never a link
            if folder.is_symlink():
                folder.unlink()
        target.parent.mkdir(parents=True, exist_ok=True)
        for path, text in ((target.parent / twin.room_name, twin.room_text),
                           (target, twin.mission_text)):
            data = text.encode("utf-8")
            if path.is_symlink() or not path.is_file() or path.read_bytes() != data:
                write_atomic(path, data)
        written.append(target)
    return written
