"""Find every place a declared name is written, and what renaming it would change.

Rename and find-references for the names a user declares: in a room its floors (explicit
ones and grid cells named by a legend), walls, objects, humans, the robot and grids; in a
mission its goals (and, through its ``in "…"`` import, the room's floors); in a .vepl file
its parameters, functions, queries (and their parameters), query and complex events,
signals and requirements. A room's names are also written in the missions that import it,
so their places are looked up in every mission of the workspace.

Occurrences are found on the tokens of the text as the editor holds it (comments and
strings skipped, keywords and catalogue types never taken for names) and kept only where
the last checked model declares the name, so a half-typed file still renames right.
This module never edits a file and never checks a rule: it answers with places, or with
the reason a rename is refused (not an identifier, a keyword, a clash, a name the grid
makes up), which the editor shows.
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any

from rei.lang.errors import Diagnostic, Span
from rei.lang.room.model import Room
from rei.lang.source import read_bounded

__all__ = ["Occurrence", "RenameRefused", "Target", "room_references", "vepl_occurrences",
           "check_new_name", "tokens"]

MAX_WORKSPACE_MISSIONS = 2000
"""Mission files read from the disk when looking for a room's references (a bound, so a
workspace rooted at / cannot stall the server)."""
MAX_WORKSPACE_FOLDERS = 20_000
"""Folders walked looking for them (the same bound, for a tree with few missions)."""
_SKIPPED_FOLDERS = {"node_modules", "__pycache__", "site-packages", "build", "dist"}

_TOKEN = re.compile(
    r"(?P<comment>//[^\n]*|/\*.*?(?:\*/|\Z))"
    r"|(?P<string>\"(?:[^\"\\\n]|\\.)*\"?|'(?:[^'\\\n]|\\.)*'?)"
    r"|(?P<number>\d[\w.]*)"
    r"|(?P<name>[^\W\d]\w*)"
    r"|(?P<punct>\S)", re.S)
IDENTIFIER = re.compile(r"[^\W\d]\w*")


@dataclass(frozen=True)
class Token:
    start: int
    end: int
    text: str
    name: bool
    """An identifier (not a string, comment, number or punctuation)."""


def tokens(text: str) -> list[Token]:
    """The tokens of a REI file (all three languages share comments, strings and names)."""
    out: list[Token] = []
    for match in _TOKEN.finditer(text):
        kind = match.lastgroup
        if kind in ("comment", "string"):
            continue
        out.append(Token(match.start(), match.end(), match.group(0), kind == "name"))
    return out


@cache
def keywords(*grammars: str) -> frozenset[str]:
    """The keywords of the given grammar files (a name must never become one)."""
    words: set[str] = set()
    folder = resources.files("rei.grammars")
    for grammar in grammars:
        text = folder.joinpath(grammar).read_text(encoding="utf-8")
        text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
        words.update(re.findall(r"'([^\W\d]\w*)'", text))
    return frozenset(words)


ROOM_KEYWORDS = ("room.tx", "common.tx")
MISSION_KEYWORDS = ("mission.tx", "mission_fault.tx", "common.tx")
VEPL_KEYWORDS = ("vepl.tx", "common.tx")
VEPL_BUILTINS = frozenset({"robot", "distance", "on", "state", "failure", "approach", "goal",
                           "neighbours", "mission_state", "nav_state", "object", "floor",
                           "task"})
RUNTIME_PARAMETERS = frozenset({"eps_close", "eps_collision", "hysteresis"})
"""Parameters the runtime reads by name: renaming one would silently change its meaning."""


class RenameRefused(Exception):
    """A rename that cannot be done; the message says why (the editor shows it)."""


@dataclass(frozen=True)
class Occurrence:
    """One place a name is written: a file, its text, and where in it (REI 1-based span)."""

    path: str
    text: str
    span: Span
    declaration: bool


@dataclass(frozen=True)
class Target:
    """The declared thing a cursor is on."""

    name: str
    kind: str
    """floor, wall, object, grid, grid cell, goal, parameter, function, query, event,
    signal, requirement or query parameter."""
    language: str
    """room, mission or vepl: the file that declares it."""
    path: str
    refused: str | None = None
    """Why it cannot be renamed (None: it can)."""
    scope: tuple[int, int] | None = None
    """For a query's parameter: the text offsets of the declaration it belongs to."""


# --- positions ------------------------------------------------------------------------------

def offset_of(text: str, line: int, col: int) -> int:
    """The text offset of a 1-based REI line and column (clamped)."""
    start = 0
    for _ in range(line - 1):
        found = text.find("\n", start)
        if found < 0:
            return len(text)
        start = found + 1
    end = text.find("\n", start)
    end = len(text) if end < 0 else end
    return min(start + max(col - 1, 0), end)


def span_of(path: str, text: str, start: int, end: int) -> Span:
    line = text.count("\n", 0, start) + 1
    line_start = text.rfind("\n", 0, start) + 1
    col = start - line_start + 1
    return Span(path, line, col, line, col + (end - start))


def token_at(toks: list[Token], offset: int) -> Token | None:
    """The identifier touching the offset (the cursor right after a name is on it)."""
    for token in toks:
        if token.start <= offset <= token.end and token.name:
            return token
        if token.start > offset:
            break
    return None


def _previous(toks: list[Token], i: int) -> Token | None:
    return toks[i - 1] if i > 0 else None


# --- rooms ----------------------------------------------------------------------------------

def _auto_cell(room: Room, name: str) -> tuple[str, int, int] | None:
    """(grid, row, column) when the name is one a grid made up for an unnamed cell."""
    decl = room.floors.get(name) or room.walls.get(name)
    cell = getattr(decl, "cell_of_grid", None)
    if cell is None or name != f"{cell.grid}_{cell.row}_{cell.col}":
        return None
    return cell.grid, cell.row, cell.col


def room_kind(room: Room, name: str) -> str | None:
    if _auto_cell(room, name) is not None:
        return "grid cell"
    if name in room.floors:
        return "floor"
    if name in room.walls:
        return "wall"
    for obj in room.objects:
        if obj.name == name:
            return obj.role if obj.role in ("robot", "human") else "object"
    if any(grid.name == name for grid in room.grids):
        return "grid"
    return None


def room_declared(room: Room) -> dict[str, str]:
    """Every name a room declares, with what it is."""
    names: dict[str, str] = {}
    for name in [*room.floors, *room.walls, *(o.name for o in room.objects),
                 *(g.name for g in room.grids)]:
        kind = room_kind(room, name)
        if kind is not None:
            names.setdefault(name, kind)
    return names


def room_target(room: Room, path: str, name: str) -> Target | None:
    kind = room_kind(room, name)
    if kind is None:
        return None
    refused = None
    if kind == "grid cell":
        grid, row, col = _auto_cell(room, name) or ("", 0, 0)
        refused = (f"'{name}' is the name grid '{grid}' gives its cell at row {row}, column "
                   f"{col}; to rename it, give the cell a name in the grid's legend")
    return Target(name, kind, "room", path, refused)


def room_name_tokens(toks: list[Token]) -> Iterator[tuple[int, Token]]:
    """Identifiers of a room text that can be names of floors, walls, objects or grids
    (not keywords, not the catalogue type after ':', not a human's behaviour)."""
    words = keywords(*ROOM_KEYWORDS)
    for i, token in enumerate(toks):
        if not token.name or token.text in words:
            continue
        before = _previous(toks, i)
        if before is not None and before.text in (":", "behaviour", "room"):
            continue
        yield i, token


def room_occurrences(room: Room, path: str, text: str, name: str,
                     kind: str) -> list[Occurrence]:
    """The places a room's own file writes the name (for a grid: its name, and its name as
    the prefix of every made-up cell name)."""
    out: list[Occurrence] = []
    toks = tokens(text)
    if kind == "grid":
        for i, token in enumerate(toks):
            before = _previous(toks, i)
            if token.text == name and before is not None and before.text == "grid":
                out.append(Occurrence(path, text, span_of(path, text, token.start, token.end),
                                      True))
        return out + cell_prefixes(room, path, text, name, toks)
    declaring = {"floor", "wall", "object", "dynamic", "human", "robot"}
    for i, token in room_name_tokens(toks):
        if token.text != name:
            continue
        before = _previous(toks, i)
        is_declaration = before is not None and before.text in declaring
        out.append(Occurrence(path, text, span_of(path, text, token.start, token.end),
                              is_declaration))
    return out


def cell_prefixes(room: Room, path: str, text: str, grid: str, toks: list[Token]
                  ) -> list[Occurrence]:
    """Where a text names a cell that grid ``grid`` named by its place (``hall_2_3``): the
    grid's part of that name, which renaming the grid changes."""
    cell = re.compile(rf"{re.escape(grid)}_\d+_\d+")
    return [Occurrence(path, text, span_of(path, text, t.start, t.start + len(grid)), False)
            for t in toks if t.name and cell.fullmatch(t.text)
            and room_kind(room, t.text) == "grid cell"]


# --- missions -------------------------------------------------------------------------------

_MISSION_HEAD = re.compile(r"\bmission\s+[^\W\d]\w*\s+in\s+\"([^\"\n]*)\"")


def imported_room(mission_path: str, text: str) -> str | None:
    """The resolved path of the room a mission text imports, read from its header."""
    match = _MISSION_HEAD.search(_without_comments(text))
    if match is None:
        return None
    return _resolved(str(Path(mission_path).parent / match.group(1)))


def _without_comments(text: str) -> str:
    return re.sub(r"//[^\n]*|/\*.*?\*/", lambda m: " " * len(m.group(0)), text, flags=re.S)


def mission_floor_occurrences(path: str, text: str, name: str) -> list[Occurrence]:
    """Where a mission names a floor of its room: after a goal's ``at``."""
    toks = tokens(text)
    out = []
    for i, token in enumerate(toks):
        before = _previous(toks, i)
        if token.text == name and before is not None and before.text == "at":
            out.append(Occurrence(path, text, span_of(path, text, token.start, token.end), False))
    return out


def goal_names(text: str) -> dict[str, int]:
    """The goals a mission text names, by name: the offset of the name."""
    toks = tokens(text)
    out: dict[str, int] = {}
    for i, token in enumerate(toks[:-1]):
        before = _previous(toks, i)
        if (before is not None and before.text == "goal" and token.name
                and token.text != "at"):
            out.setdefault(token.text, token.start)
    return out


def mission_target(text: str, path: str, token: Token, room: Room | None,
                   room_path: str | None) -> Target | None:
    toks = tokens(text)
    index = next((i for i, t in enumerate(toks) if t.start == token.start), None)
    if index is None:
        return None
    before = _previous(toks, index)
    if before is not None and before.text == "goal" and token.text != "at":
        return Target(token.text, "goal", "mission", path)
    if before is not None and before.text == "at" and room is not None and room_path:
        return room_target(room, room_path, token.text)
    return None


def goal_occurrences(path: str, text: str, name: str) -> list[Occurrence]:
    start = goal_names(text).get(name)
    if start is None:
        return []
    return [Occurrence(path, text, span_of(path, text, start, start + len(name)), True)]


# --- .vepl ----------------------------------------------------------------------------------

_VEPL_SECTIONS = (("parameters", "parameter"), ("functions", "function"),
                  ("queries", "query"), ("query_events", "event"),
                  ("complex_events", "event"), ("signals", "signal"),
                  ("requirements", "requirement"))
_VEPL_DECLARING = {"function", "query", "queryEvent", "complexEvent", "signal", "requirement"}


def vepl_declared(spec: Any) -> dict[str, str]:
    names: dict[str, str] = {}
    for attribute, kind in _VEPL_SECTIONS:
        section = getattr(spec, attribute, None) or ()
        items = section if isinstance(section, dict) else [
            getattr(d, "name", None) for d in section]
        for name in items:
            if isinstance(name, str):
                names.setdefault(name, kind)
    return names


def _declaration_ranges(toks: list[Token]) -> list[tuple[int, int, set[str]]]:
    """(start, end, local names) of each query and query event: the names in its first
    parenthesised list are its own parameters, seen only inside it."""
    out = []
    starts = [i for i, t in enumerate(toks) if t.text in _VEPL_DECLARING
              or t.text == "parameters"]
    for n, i in enumerate(starts):
        end = toks[starts[n + 1]].start if n + 1 < len(starts) else (
            toks[-1].end if toks else 0)
        if toks[i].text not in ("query", "queryEvent"):
            continue
        local: set[str] = set()
        depth = 0
        j = i + 2
        if j < len(toks) and toks[j].text == "(":
            j += 1
            while j < len(toks) and toks[j].text != ")":
                t = toks[j]
                if t.text == "[":
                    depth += 1
                elif t.text == "]":
                    depth -= 1
                elif t.name and depth == 0 and toks[j - 1].text in ("(", ","):
                    local.add(t.text)
                j += 1
        out.append((toks[i].start, end, local))
    return out


def local_names(text: str, scope: tuple[int, int]) -> dict[str, str]:
    """The parameters of the query or query event at ``scope``."""
    for start, _, local in _declaration_ranges(tokens(text)):
        if start == scope[0]:
            return {name: "query parameter" for name in local}
    return {}


def vepl_target(spec: Any, text: str, path: str, token: Token) -> Target | None:
    toks = tokens(text)
    for start, end, local in _declaration_ranges(toks):
        if start <= token.start < end and token.text in local:
            return Target(token.text, "query parameter", "vepl", path, scope=(start, end))
    kind = vepl_declared(spec).get(token.text)
    if kind is None:
        return None
    refused = None
    if kind == "parameter" and token.text in RUNTIME_PARAMETERS:
        refused = (f"parameter '{token.text}' is read by name by REI's monitor; a new name "
                   f"would silently drop its setting")
    return Target(token.text, kind, "vepl", path, refused)


def vepl_occurrences(target: Target, text: str) -> list[Occurrence]:
    toks = tokens(text)
    words = keywords(*VEPL_KEYWORDS)
    ranges = _declaration_ranges(toks)
    out = []
    for i, token in enumerate(toks):
        if token.text != target.name or not token.name or token.text in words:
            continue
        if target.scope is not None:
            if not target.scope[0] <= token.start < target.scope[1]:
                continue
            before = _previous(toks, i)
            declaration = before is not None and before.text in ("(", ",") and any(
                s == target.scope[0] for s, _, _ in ranges) and _in_header(toks, i)
        else:
            if any(s <= token.start < e and target.name in local for s, e, local in ranges):
                continue  # a query parameter of the same name hides it here
            before = _previous(toks, i)
            following = toks[i + 1] if i + 1 < len(toks) else None
            declaration = before is not None and (
                before.text in _VEPL_DECLARING
                or (target.kind == "parameter" and following is not None
                    and following.text == "="))
        out.append(Occurrence(target.path, text,
                              span_of(target.path, text, token.start, token.end), declaration))
    return out


def _in_header(toks: list[Token], i: int) -> bool:
    """Whether token i is inside the first parenthesis of its declaration."""
    j = i
    while j > 0 and toks[j].text not in _VEPL_DECLARING:
        if toks[j].text in (")", "{"):
            return False
        j -= 1
    return True


# --- the workspace --------------------------------------------------------------------------

def _resolved(path: str) -> str:
    try:
        return str(Path(path).resolve())
    except (OSError, RuntimeError, ValueError):
        return os.path.abspath(path)


def mission_files(roots: Iterable[str], limit: int = MAX_WORKSPACE_MISSIONS) -> list[str]:
    """The .mission files under the workspace folders (hidden and tool folders skipped,
    at most ``limit``)."""
    found: list[str] = []
    seen: set[str] = set()
    folders = 0
    for root in roots:
        for folder, subfolders, files in os.walk(root):
            folders += 1
            if folders > MAX_WORKSPACE_FOLDERS:
                return found
            subfolders[:] = sorted(d for d in subfolders
                                   if not d.startswith(".") and d not in _SKIPPED_FOLDERS)
            for name in sorted(files):
                if name.endswith(".mission"):
                    path = _resolved(os.path.join(folder, name))
                    if path not in seen:
                        seen.add(path)
                        found.append(path)
                        if len(found) >= limit:
                            return found
    return found


def read_text(path: str) -> str | None:
    data = read_bounded(path)
    if isinstance(data, Diagnostic):
        return None
    return data.decode("utf-8", errors="replace")


def room_references(room: Room, room_path: str, target: Target,
                    text_of: Callable[[str], str | None],
                    missions: Iterable[str]) -> list[Occurrence]:
    """Every place the room's name is written: the room file and each mission importing it."""
    room_text = text_of(room_path)
    out = room_occurrences(room, room_path, room_text or "", target.name, target.kind) \
        if room_text is not None else []
    key = _resolved(room_path)
    for mission in missions:
        text = text_of(mission)
        if text is None or imported_room(mission, text) != key:
            continue
        if target.kind == "grid":
            out.extend(cell_prefixes(room, mission, text, target.name, tokens(text)))
        else:
            out.extend(mission_floor_occurrences(mission, text, target.name))
    return out


def check_new_name(target: Target, new_name: str, declared: dict[str, str]) -> None:
    """Raise RenameRefused when ``new_name`` is not a name the target's file can hold."""
    if target.refused is not None:
        raise RenameRefused(target.refused)
    if IDENTIFIER.fullmatch(new_name) is None:
        raise RenameRefused(f"expected an identifier (a letter or '_', then letters, digits "
                            f"or '_'), found '{new_name}'")
    if new_name == target.name:
        return
    languages = {"room": ROOM_KEYWORDS + MISSION_KEYWORDS, "mission": MISSION_KEYWORDS,
                 "vepl": VEPL_KEYWORDS}[target.language]
    if new_name in keywords(*languages):
        raise RenameRefused(f"'{new_name}' is a keyword of the {target.language} language")
    if target.language == "vepl" and new_name in VEPL_BUILTINS:
        raise RenameRefused(f"'{new_name}' is a name the .vepl language already gives "
                            f"meaning to")
    if target.kind == "grid":
        made_up = re.compile(rf"{re.escape(new_name)}_\d+_\d+")
        clash = next((n for n in declared if made_up.fullmatch(n)), None)
        if clash is not None:
            raise RenameRefused(f"renaming grid '{target.name}' to '{new_name}' would name "
                                f"its cells like '{clash}', which is already declared")
    if new_name in declared:
        raise RenameRefused(f"'{new_name}' is already the name of a {declared[new_name]} "
                            f"in this {target.language} file")
