"""Rendering pictures to PNG or SVG bytes, deterministically, without a display.

The Agg canvas is attached to each Figure explicitly (no pyplot, no global figure manager,
no window), SVG output has a fixed hash salt and no date, and PNG output carries no software
version, so the same input gives the same bytes. Contact sheets draw many rooms on one image
from a folder or from an index CSV (columns ``room`` and/or ``mission``, paths relative to
the CSV, optional ``name``). This module must never write files: it returns bytes.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path

import matplotlib
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from rei.generators.concrete import ConcreteMission, ConcreteWorld
from rei.generators.errors import GenerationError
from rei.generators.picture.draw import draw_world
from rei.lang.errors import Diagnostic, LanguageError, Span
from rei.lang.source import UnreadableInput, bounded_text
from rei.lang.workspace import Workspace

FORMATS = ("png", "svg")
SVG_SALT = "rei"
DPI = 150
SHEET_DPI = 90


@dataclass(frozen=True)
class SheetEntry:
    title: str
    path: Path


def _concrete(path: Path, workspace: Workspace) -> tuple[ConcreteWorld, ConcreteMission | None]:
    from rei.generators.pipeline import build_request  # noqa: PLC0415  (pipeline imports targets)

    request, _ = build_request(path, None, workspace)
    if request.world is None:
        raise GenerationError(f"expected a .room or .mission file to draw, found '{path.name}'")
    return request.world, request.mission


def _save(fig: Figure, fmt: str) -> bytes:
    if fmt not in FORMATS:
        raise GenerationError(f"expected a picture format among {', '.join(FORMATS)}, "
                              f"found '{fmt}'")
    FigureCanvasAgg(fig)
    buffer = io.BytesIO()
    with matplotlib.rc_context({"svg.hashsalt": SVG_SALT}):
        if fmt == "svg":
            fig.savefig(buffer, format="svg", metadata={"Date": None, "Creator": None})
        else:
            fig.savefig(buffer, format="png", metadata={"Software": None})
    return buffer.getvalue()


def render_concrete(world: ConcreteWorld, mission: ConcreteMission | None, fmt: str) -> bytes:
    """One room (with the mission's goals) as PNG or SVG bytes."""
    min_x, min_y, max_x, max_y = world.bounds()
    width, height = max_x - min_x, max_y - min_y
    # About 0.55 inch per metre, kept readable for tiny rooms and bounded for huge ones;
    # 2.6 inches on the right hold the legend.
    scale = min(0.55, 14.0 / max(width, 1e-9), 10.0 / max(height, 1e-9))
    scale = max(scale, 2.5 / max(width, height, 1e-9))
    fig = Figure(figsize=(width * scale + 3.6, height * scale + 1.2), dpi=DPI,
                 layout="constrained")
    draw_world(fig.add_subplot(), world, mission)
    return _save(fig, fmt)


def render_file(path: Path, fmt: str, workspace: Workspace | None = None) -> bytes:
    """The picture of a .room or .mission file; LanguageError when the file is invalid."""
    world, mission = _concrete(Path(path), workspace or Workspace())
    return render_concrete(world, mission, fmt)


def sheet_entries(path: Path) -> list[SheetEntry]:
    """The rooms of a contact sheet: from a folder (missions, then rooms no mission uses) or
    from an index CSV (a mission when the row has one, else its room)."""
    path = Path(path)
    if path.is_dir():
        missions = sorted(p for p in path.rglob("*.mission") if p.is_file())
        rooms = sorted(p for p in path.rglob("*.room") if p.is_file())
        used = {p.with_suffix(".room").resolve() for p in missions}
        ws = Workspace()
        for mission in missions:
            doc = ws.mission(mission)
            if doc.mission is not None:
                used.add((mission.parent / doc.mission.room_path).resolve())
        entries = [SheetEntry(p.stem, p) for p in missions]
        entries += [SheetEntry(p.stem, p) for p in rooms if p.resolve() not in used]
        return entries
    if path.suffix.lower() == ".csv":
        return _csv_entries(path)
    raise GenerationError(f"expected a folder or an index .csv for a contact sheet, found "
                          f"'{path}'")


def _csv_entries(path: Path) -> list[SheetEntry]:
    try:
        reader = csv.DictReader(io.StringIO(bounded_text(path), newline=""))
        rows = list(reader)
        columns = list(reader.fieldnames or ())
    except (UnreadableInput, csv.Error) as exc:
        raise GenerationError(f"cannot read the index '{path}': {exc}") from None
    if not {"room", "mission"} & set(columns):
        raise LanguageError([Diagnostic(Span.point(str(path)), "INDEX-COLUMNS",
                                        f"expected a 'room' or 'mission' column, found "
                                        f"{', '.join(columns) or 'an empty file'}")])
    entries = []
    for number, row in enumerate(rows, start=2):  # line 1 is the header
        relative = (row.get("mission") or "").strip() or (row.get("room") or "").strip()
        if not relative:
            raise LanguageError([Diagnostic(Span.point(str(path), number), "INDEX-ROW",
                                            "expected a room or mission path, found none")])
        file = path.parent / relative
        entries.append(SheetEntry((row.get("name") or "").strip() or file.stem, file))
    return entries


def render_sheet(entries: list[SheetEntry], fmt: str, workspace: Workspace | None = None) -> bytes:
    """A grid of small drawings, one per entry; LanguageError with every invalid file's problems."""
    if not entries:
        raise GenerationError("expected at least one room or mission for the contact sheet, "
                              "found none")
    ws = workspace or Workspace()
    drawn: list[tuple[SheetEntry, ConcreteWorld, ConcreteMission | None]] = []
    problems: list[Diagnostic] = []
    for entry in entries:
        try:
            world, mission = _concrete(entry.path, ws)
        except LanguageError as exc:
            problems.extend(exc.diagnostics)
            continue
        drawn.append((entry, world, mission))
    if problems:
        raise LanguageError(problems)
    columns = math.ceil(math.sqrt(len(drawn)))
    rows = math.ceil(len(drawn) / columns)
    panel = 3.0
    fig = Figure(figsize=(columns * panel, rows * panel), dpi=SHEET_DPI, layout="constrained")
    axes = fig.subplots(rows, columns, squeeze=False)
    for index, ax in enumerate(axes.flat):
        if index >= len(drawn):
            ax.set_axis_off()
            continue
        entry, world, mission = drawn[index]
        draw_world(ax, world, mission, compact=True, title=entry.title)
    return _save(fig, fmt)
