"""A failing case as text: its .room and .mission, what can be removed from them, and edits.

A shrinking step edits the concrete scenario *text* at the source positions REI's own linker
reports (rei.lang.room / rei.lang.mission), so the result keeps the user's layout, grid and
comments, and a candidate is judged by the same checks as a hand-written file
(``ScenarioCase.problems``: the rules of `rei-gen check`). This module must never run a
simulation; it only reads and rewrites text.
"""

from __future__ import annotations

import hashlib
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

from rei.lang.errors import Diagnostic, LanguageError, Span
from rei.lang.mission.model import Mission
from rei.lang.room.linker import DEFAULT_LEGEND
from rei.lang.room.model import Room
from rei.lang.source import read_source
from rei.lang.workspace import Workspace

ELEMENT_KINDS = ("humans", "dynamic_objects", "objects", "goals", "floors",
                 "trajectory_vertices")
"""What a case is made of, in the order shrink.json counts it; ``elements`` is their sum."""

_ROLE_KIND = {"human": "humans", "dynamic": "dynamic_objects", "static": "objects"}

NUMBER_SETTINGS = re.compile(
    r"\b(heading_tolerance|heading|at|tolerance|timeout|total|time_limit|settle|max_speed)"
    r"(\s+)([-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?)(?![\w.])")
"""A setting followed by a number: the numbers shrinking may round (a goal's `at FLOOR`
is followed by a name, never matched)."""


@dataclass(frozen=True)
class Element:
    """One removable part of a case: a human, object, goal, grid floor or trajectory vertex."""

    kind: str
    label: str
    """What a user calls it: the name, ``goal 2 (elevator)``, ``walker vertex 3``."""
    file: str
    """``room`` or ``mission``."""
    start: int
    end: int
    """Character offsets of its text; a grid floor is its one cell character."""
    owner: str = ""
    """A vertex's human or object (a trajectory keeps two vertices at the least)."""


@dataclass(frozen=True)
class NumberSite:
    """A number shrinking may round: its offsets in one file and its text."""

    file: str
    start: int
    end: int
    text: str


@dataclass(frozen=True)
class ScenarioCase:
    """One room and one mission that imports it by file name, as texts."""

    mission_name: str
    """File name of the .mission (``to_the_elevator.mission``)."""
    mission_text: str
    room_name: str
    room_text: str

    def digest(self) -> str:
        """Identity of a candidate: equal texts are the same case (results are cached by it)."""
        h = hashlib.sha256()
        for part in (self.mission_name, self.mission_text, self.room_name, self.room_text):
            h.update(part.encode("utf-8"))
            h.update(b"\0")
        return h.hexdigest()

    def write(self, folder: Path) -> Path:
        """Write both files into ``folder``; the mission's path."""
        folder.mkdir(parents=True, exist_ok=True)
        (folder / self.room_name).write_text(self.room_text, encoding="utf-8")
        mission = folder / self.mission_name
        mission.write_text(self.mission_text, encoding="utf-8")
        return mission

    def text(self, file: str) -> str:
        return self.room_text if file == "room" else self.mission_text

    def with_text(self, file: str, text: str) -> ScenarioCase:
        return replace(self, room_text=text) if file == "room" else replace(self,
                                                                            mission_text=text)

    def models(self) -> tuple[Room, Mission, list[Diagnostic]]:
        """The linked room and mission and the errors `rei-gen check` would report on them
        (as if both files lay in one folder); LanguageError when either does not parse."""
        workspace, mission_path, room_path = self._workspace()
        mission_doc = workspace.mission(mission_path)
        room_doc = workspace.room(room_path)
        errors = [d for d in (*mission_doc.diagnostics, *room_doc.diagnostics) if d.is_error]
        if mission_doc.mission is None or room_doc.room is None:
            raise LanguageError(errors)
        return room_doc.room, mission_doc.mission, errors

    def problems(self) -> list[Diagnostic]:
        """Errors of the case under the rules of `rei-gen check` (empty: it checks clean)."""
        try:
            return self.models()[2]
        except LanguageError as exc:
            return list(exc.diagnostics)

    def _workspace(self) -> tuple[Workspace, Path, Path]:
        # The files are judged where they would be written; only their texts are used.
        folder = Path("/rei-shrink-candidate")
        workspace = Workspace()
        workspace.set_text(folder / self.mission_name, self.mission_text)
        workspace.set_text(folder / self.room_name, self.room_text)
        return workspace, folder / self.mission_name, folder / self.room_name


def load_case(mission_path: Path) -> ScenarioCase:
    """The case of a .mission file and the room it imports, made self-contained: the mission
    imports the room by its file name and a relative catalogue path becomes absolute, so the
    two files can be written into any folder. LanguageError when either does not check clean
    (a case must be valid before it is shrunk)."""
    workspace = Workspace()
    doc = workspace.mission(mission_path)
    room_doc = doc.room
    errors = [d for d in doc.diagnostics if d.is_error]
    if room_doc is not None:
        errors += [d for d in room_doc.diagnostics if d.is_error]
    if errors or doc.mission is None or room_doc is None or room_doc.room is None \
            or doc.source is None or room_doc.source is None:
        raise LanguageError(errors or [Diagnostic(Span.point(str(mission_path)), "SHRINK-INPUT",
                                                  "expected a mission that checks clean")])
    mission, room = doc.mission, room_doc.room
    room_file = Path(room_doc.source.path)
    mission_text = doc.source.text
    start, end = _offsets(mission_text, mission.room_span)
    mission_text = mission_text[:start] + f'"{room_file.name}"' + mission_text[end:]
    room_text = room_doc.source.text
    if room.catalogue_path is not None and room.catalogue_span is not None:
        start, end = _offsets(room_text, room.catalogue_span)
        quoted = room_text.find('"', start)
        closing = room_text.find('"', quoted + 1)
        if 0 <= quoted < closing:
            absolute = str(Path(room.catalogue_path).resolve())
            room_text = room_text[:quoted] + f'"{absolute}"' + room_text[closing + 1:]
    case = ScenarioCase(Path(mission_path).name, mission_text, room_file.name, room_text)
    problems = case.problems()
    if problems:  # e.g. a file name REI cannot import from one folder
        raise LanguageError(problems)
    return case


def read_case(folder: Path, mission_name: str, room_name: str) -> ScenarioCase:
    """A case written by ``ScenarioCase.write`` (the best case of an earlier shrink)."""
    texts = []
    for name in (mission_name, room_name):
        source = read_source(folder / name)
        if isinstance(source, Diagnostic):
            raise LanguageError([source])
        texts.append(source.text)
    return ScenarioCase(mission_name, texts[0], room_name, texts[1])


def _line_starts(text: str) -> list[int]:
    starts = [0]
    starts.extend(m.end() for m in re.finditer("\n", text))
    return starts


def _offsets(text: str, span: Span) -> tuple[int, int]:
    starts = _line_starts(text)
    return (starts[span.line - 1] + span.col - 1, starts[span.end_line - 1] + span.end_col - 1)


def elements(case: ScenarioCase) -> list[Element]:
    """Every removable part of ``case`` (it must parse), in file order per kind; a mission's
    ``cycles`` setting is one too (kind ``cycles``: not counted by ``sizes``)."""
    room, mission, _ = case.models()
    out: list[Element] = []
    for obj in room.objects:
        if obj.role == "robot":
            continue
        start, end = _offsets(case.room_text, obj.span)
        out.append(Element(_ROLE_KIND[obj.role], obj.name, "room", start, end))
        if obj.trajectory is not None:
            for number, vertex in enumerate(obj.trajectory.vertices, start=1):
                v_start, v_end = _offsets(case.room_text, vertex.span)
                out.append(Element("trajectory_vertices", f"{obj.name} vertex {number}", "room",
                                   v_start, v_end, owner=obj.name))
    if mission.cycles != 1:  # one pass through the goals is the shorter mission
        found = _CYCLES.search(_mask_comments(case.mission_text))
        if found is not None:
            out.append(Element("cycles", found.group(0), "mission", found.start(), found.end()))
    for number, goal in enumerate(mission.goals, start=1):
        start, end = _offsets(case.mission_text, goal.span)
        label = f"goal {number}" + (f" ({goal.name})" if goal.name else "")
        out.append(Element("goals", label, "mission", start, end))
    for floor in room.floors.values():
        if floor.cell_of_grid is None:
            continue  # an explicit floor is linked by name from others: not dropped (see docs)
        start, _ = _offsets(case.room_text, floor.span)
        out.append(Element("floors", floor.name, "room", start, start + 1))
    return out


def sizes(case: ScenarioCase) -> dict[str, int]:
    """How big the case is: a count per element kind (every floor, explicit ones too, though
    only grid floors are dropped), their sum (``elements``), and the characters of both files
    (``characters``)."""
    room, mission, _ = case.models()
    counts = dict.fromkeys(ELEMENT_KINDS, 0)
    for obj in room.objects:
        if obj.role != "robot":
            counts[_ROLE_KIND[obj.role]] += 1
            if obj.trajectory is not None:
                counts["trajectory_vertices"] += len(obj.trajectory.vertices)
    counts["goals"] = len(mission.goals)
    counts["floors"] = len(room.floors)
    counts["elements"] = sum(counts[k] for k in ELEMENT_KINDS)
    counts["characters"] = len(case.room_text) + len(case.mission_text)
    return counts


def wall_symbol(room_text: str, grid_start: int, grid_end: int) -> str:
    """The symbol a grid's legend (or the default legend) gives a plain wall."""
    legend = re.search(r"legend\s*\{(.*?)\}", room_text[grid_start:grid_end], re.S)
    if legend is not None:
        for match in re.finditer(r'"(.)"\s*=\s*wall(?![\w:])(?!\s+[A-Za-z_])', legend.group(1)):
            return match.group(1)
        overridden = {m.group(1) for m in re.finditer(r'"(.)"\s*=', legend.group(1))}
        if "#" in overridden:
            return "#"  # '#' means something else here: the candidate fails its check
    return next(s for s, kind in DEFAULT_LEGEND.items() if kind == "wall")


def without(case: ScenarioCase, removed: Iterable[Element]) -> ScenarioCase:
    """``case`` without ``removed`` (elements of this very case): items and vertices are cut
    with their line when alone on it (and a comment block right above an item goes with it);
    a grid floor becomes a wall cell."""
    by_file: dict[str, list[Element]] = {"room": [], "mission": []}
    for element in removed:
        by_file[element.file].append(element)
    result = case
    for file, items in by_file.items():
        text = case.text(file)
        for element in sorted(items, key=lambda e: e.start, reverse=True):
            if element.kind == "floors":
                grid_start = text.rfind("grid", 0, element.start)
                grid_end = text.find("}", element.start)
                symbol = wall_symbol(text, max(grid_start, 0), grid_end)
                text = text[:element.start] + symbol + text[element.end:]
            else:
                text = _cut(text, element.start, element.end,
                            with_comment=element.kind != "trajectory_vertices")
        if items and any(e.kind != "floors" for e in items):
            text = _tidy(text)
        result = result.with_text(file, text)
    return result


def _tidy(text: str) -> str:
    """No run of blank lines, and no blank line right before a closing brace, where items
    were cut."""
    text = re.sub(r"\n[ \t]*\n(?:[ \t]*\n)+", "\n\n", text)
    return re.sub(r"\n[ \t]*\n([ \t]*\})", r"\n\1", text)


_CYCLES = re.compile(r"\bcycles\s+\S+")


_COMMENT_LINE = re.compile(r"[ \t]*//[^\n]*\n$")


def _cut(text: str, start: int, end: int, with_comment: bool) -> str:
    line_start = text.rfind("\n", 0, start) + 1
    line_end = text.find("\n", end)
    line_end = len(text) if line_end < 0 else line_end
    alone = not text[line_start:start].strip() and not text[end:line_end].strip()
    if not alone:
        # cut the item and the blanks before it ("wall a  wall b" -> "wall a")
        while start > 0 and text[start - 1] in " \t":
            start -= 1
        return text[:start] + text[end:]
    cut_from = line_start
    if with_comment:
        while cut_from > 0:
            previous = text.rfind("\n", 0, cut_from - 1) + 1
            if not _COMMENT_LINE.match(text[previous:cut_from]):
                break
            cut_from = previous
    return text[:cut_from] + text[min(line_end + 1, len(text)):]


def number_sites(case: ScenarioCase) -> list[NumberSite]:
    """Numbers of settings (headings, times, tolerances, timeouts, limits) in both files,
    outside comments, that have a fractional part or more than one significant digit."""
    sites = []
    for file in ("room", "mission"):
        text = case.text(file)
        masked = _mask_comments(text)
        for match in NUMBER_SETTINGS.finditer(masked):
            sites.append(NumberSite(file, match.start(3), match.end(3), match.group(3)))
    return sites


def _mask_comments(text: str) -> str:
    def blank(match: re.Match[str]) -> str:
        return re.sub(r"[^\n]", " ", match.group(0))

    return re.sub(r'"[^"\n]*"|//[^\n]*|/\*.*?\*/', blank, text, flags=re.S)


def rounded(text: str) -> list[str]:
    """Shorter spellings of a number, the shortest first: whole, then one decimal; none when
    it is already written that short."""
    try:
        value = float(text)
    except ValueError:
        return []
    out = []
    for digits in (0, 1):
        candidate = f"{round(value, digits):.{digits}f}"
        if candidate.startswith("-") and float(candidate) == 0:
            candidate = candidate[1:]
        if len(candidate) < len(text) and candidate not in out:
            out.append(candidate)
    return out


def with_numbers(case: ScenarioCase, changes: Sequence[tuple[NumberSite, str]]) -> ScenarioCase:
    """``case`` with each site's number replaced by its new text."""
    result = case
    for file in ("room", "mission"):
        text = case.text(file)
        for site, new in sorted((c for c in changes if c[0].file == file),
                                key=lambda c: c[0].start, reverse=True):
            text = text[:site.start] + new + text[site.end:]
        result = result.with_text(file, text)
    return result
