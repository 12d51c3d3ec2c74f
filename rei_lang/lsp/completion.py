"""Completion candidates from the text before the cursor and the last model that parsed.

While a file is being typed it usually does not parse, so the names offered come from the
last version that did (the server keeps it); the *context* (after ``on``, after ``:``,
inside a trajectory) is read from the raw text before the cursor with a small tokenizer.
Keywords come from the grammars themselves, so they cannot drift from the language. This
module must never check a rule.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Iterable
from dataclasses import dataclass
from importlib import resources

from rei.catalogue import Catalogue, default_catalogue
from rei.lang.mission.faults import ACTIVATION_KEYWORDS, KINDS
from rei.lang.mission.model import COLLECTED_DATA
from rei.lang.room.model import BEHAVIOURS, Room

_TOKEN = re.compile(r"//[^\n]*|/\*.*?(?:\*/|$)|\"[^\"\n]*\"?|'[^'\n]*'?|[A-Za-z_]\w*|"
                    r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|\S", re.DOTALL)
_WORD_END = re.compile(r"[A-Za-z_]\w*\Z")
LOOKBEHIND_CHARS = 4000
"""Context is read from at most this many characters before the cursor: completion stays
instant in a 2 MB file, and no REI statement is longer."""

SIDES = ("top", "right", "bottom", "left")
ROLE_OF_KEYWORD = {"object": "static", "dynamic": "dynamic", "human": "human",
                   "robot": "robot", "floor": "floor", "wall": "wall"}
BLOCK_OPENERS = ("room", "grid", "legend", "floor", "trajectory", "mission", "monitor", "fault")
MONITOR_KEYWORDS = ("rate", "data", "Hz")
"""Words of a mission's monitor block, offered only inside it."""
FAULT_KEYWORDS = ACTIVATION_KEYWORDS
"""Words of a fault entry, offered only inside a fault section."""
TRAJECTORY_OPTIONS = ("total", "loop", "stop", "when")
"""What may follow ``trajectory`` before its ``{``."""
TRIGGER_NEXT = {"when": "robot", "robot": "within"}
"""A start trigger (``when robot within D of FLOOR``) word by word."""
TRIGGER_WORDS = ("when", "within", "of")
"""Words of a start trigger only: offered in it, never as statements of a room."""


@functools.cache
def default_signals() -> tuple[str, ...]:
    """The signals the default specification declares: what a fault's ``when`` / ``until``
    usually names (a mission does not know which .vepl it will be run with)."""
    try:
        text = resources.files("rei.lang.vepl").joinpath("default.vepl").read_text("utf-8")
    except (OSError, ValueError):
        return ()
    return tuple(re.findall(r"^\s*signal\s+([A-Za-z_]\w*)", text, re.MULTILINE))


@functools.cache
def grammar_keywords(language: str) -> tuple[str, ...]:
    """Every keyword of a language's grammar (and the grammars it imports)."""
    words: set[str] = set()
    pending = [language]
    seen: set[str] = set()
    while pending:
        name = pending.pop()
        if name in seen:
            continue
        seen.add(name)
        try:
            text = resources.files("rei.grammars").joinpath(f"{name}.tx").read_text("utf-8")
        except (OSError, ValueError):
            continue
        text = re.sub(r"/\*.*?\*/|//[^\n]*", "", text, flags=re.DOTALL)
        words.update(re.findall(r"'([A-Za-z_]\w*)'", text))
        pending.extend(re.findall(r"^\s*import\s+(\w+)", text, re.MULTILINE))
    return tuple(sorted(words))


@dataclass(frozen=True)
class Candidate:
    label: str
    kind: str
    """keyword | floor | wall | type | query | file"""
    detail: str = ""


@dataclass(frozen=True)
class Context:
    previous: tuple[str, ...]
    """The tokens before the cursor, nearest last (a partly typed word excluded)."""
    blocks: tuple[str, ...]
    """The keywords that opened the blocks the cursor is in, innermost last."""


def context_at(text_before: str) -> Context:
    text = text_before[-LOOKBEHIND_CHARS:]
    partial = _WORD_END.search(text)
    if partial is not None:
        text = text[:partial.start()]
    tokens = [t for t in _TOKEN.findall(text) if not t.startswith(("//", "/*"))]
    blocks: list[str] = []
    for i, token in enumerate(tokens):
        if token == "{":
            opener = next((t for t in reversed(tokens[max(0, i - 12):i]) if t in BLOCK_OPENERS
                           or t == "{" or t == "}"), "")
            blocks.append(opener if opener in BLOCK_OPENERS else "")
        elif token == "}" and blocks:
            blocks.pop()
    return Context(tuple(tokens[-12:]), tuple(blocks))


def _floors(room: Room | None) -> list[Candidate]:
    if room is None:
        return []
    out: list[Candidate] = []
    for name, floor in room.floors.items():
        where = (f"grid {floor.cell_of_grid.grid} row {floor.cell_of_grid.row} col "
                 f"{floor.cell_of_grid.col}" if floor.cell_of_grid else "floor")
        out.append(Candidate(name, "floor", where))
    return out


def _walls(room: Room | None) -> list[Candidate]:
    return [Candidate(name, "wall", "wall") for name in (room.walls if room else {})]


def _types(catalogue: Catalogue | None, role: str | None) -> list[Candidate]:
    catalogue = catalogue or default_catalogue()
    names = catalogue.names(role) if role else catalogue.names()  # type: ignore[arg-type,unused-ignore]
    if not names:
        names = catalogue.names()
    out = []
    for name in names:
        object_type = catalogue.get(name)
        out.append(Candidate(name, "type", object_type.kind if object_type else ""))
    return out


def _keywords(words: Iterable[str]) -> list[Candidate]:
    return [Candidate(word, "keyword") for word in words]


def room_completions(text_before: str, room: Room | None, catalogue: Catalogue | None
                     ) -> list[Candidate]:
    ctx = context_at(text_before)
    prev = ctx.previous[-1] if ctx.previous else ""
    block = ctx.blocks[-1] if ctx.blocks else ""
    if prev == ":":
        keyword = next((t for t in reversed(ctx.previous) if t in ROLE_OF_KEYWORD), None)
        return _types(catalogue, ROLE_OF_KEYWORD.get(keyword or ""))
    if prev == "on":
        return _floors(room)
    if prev == "behaviour":
        return [Candidate(b, "keyword", "human behaviour") for b in BEHAVIOURS]
    trigger = _trigger_completions(ctx.previous, room)
    if trigger is not None:
        return trigger
    if prev in SIDES:
        return _floors(room) + _walls(room)
    if prev == "at" or prev in ("tile", "heading", "total", "catalogue"):
        return []  # a number or a path follows
    if block == "trajectory":
        return _floors(room)
    if block == "floor":
        return _keywords(SIDES)
    if block == "legend":
        if prev == "=":
            return _keywords(("floor", "wall", "empty"))
        return []
    if block == "grid":
        return _keywords(("legend",))
    if block == "room":
        return _keywords(w for w in grammar_keywords("room")
                         if w not in ("room", "legend", "empty", *TRIGGER_WORDS)
                         and w not in SIDES)
    return _keywords(("room",))


def _trigger_completions(previous: tuple[str, ...], room: Room | None
                         ) -> list[Candidate] | None:
    """Between ``trajectory`` and its ``{``: its options, a start trigger word by word, and
    the floors after its ``of``; None elsewhere."""
    opening = max((i for i, t in enumerate(previous) if t == "trajectory"), default=None)
    if opening is None or "{" in previous[opening:]:
        return None
    prev = previous[-1]
    if prev == "of":
        return _floors(room)
    if prev in TRIGGER_NEXT and (prev != "robot" or previous[-2:-1] == ("when",)):
        return _keywords((TRIGGER_NEXT[prev],))
    if prev == "within" or prev == "total":
        return []  # a number follows
    if previous[-2:-1] == ("within",):
        return _keywords(("of",))
    return [Candidate(w, "keyword", "trajectory option") for w in TRAJECTORY_OPTIONS]


def mission_completions(text_before: str, room: Room | None,
                        room_files: Iterable[str] = ()) -> list[Candidate]:
    """``room_files``: relative paths of the rooms a mission could import."""
    ctx = context_at(text_before)
    prev = ctx.previous[-1] if ctx.previous else ""
    if prev == "at":
        return _floors(room)
    if prev == "in":
        return [Candidate(f'"{name}"', "file", "room file") for name in room_files]
    if prev in ("cycles", "time_limit", "max_speed", "settle", "tolerance", "heading",
                "heading_tolerance", "timeout", "rate"):
        return []
    if ctx.blocks and ctx.blocks[-1] == "fault":
        return _fault_completions(ctx.previous)
    if ctx.blocks and ctx.blocks[-1] == "monitor":
        if prev in ("data", ","):
            return [Candidate(d, "keyword", "collected data") for d in COLLECTED_DATA]
        return _keywords(("rate", "data"))
    if ctx.blocks:
        return _keywords(w for w in grammar_keywords("mission")
                         if w not in ("mission", "in", *MONITOR_KEYWORDS, *FAULT_KEYWORDS))
    return _keywords(("mission", "in"))


def _fault_kinds() -> list[Candidate]:
    return [Candidate(k.kind, "keyword", f"fault ({k.channel}): {k.summary}")
            for k in KINDS.values()]


def _fault_completions(previous: tuple[str, ...]) -> list[Candidate]:
    """Inside ``fault { }``: a kind starts an entry; after it, its parameters not yet given
    and the activation words; after ``when`` / ``until``, the default signals."""
    prev = previous[-1] if previous else ""
    if prev in ("when", "until"):
        return [Candidate(s, "keyword", "signal of the default specification")
                for s in default_signals()]
    if prev in ("as", "from", "to", "for"):
        return []  # a name or a number follows
    at = next((i for i in range(len(previous) - 1, -1, -1) if previous[i] in KINDS), None)
    if at is None or prev in ("{", "}"):
        return _fault_kinds()
    spec = KINDS[previous[at]]
    entry = previous[at + 1:]
    if any(p.name == prev for p in spec.parameters):
        return []  # the parameter's number follows
    words = [w for w in entry if w in ("when", "until", "from", "to", "for")]
    if words:
        if words == ["from"]:
            return [Candidate("to", "keyword", "end of the window (seconds)"), *_fault_kinds()]
        if words == ["when"] and entry[-2:-1] == ("when",):
            return [Candidate("for", "keyword", "seconds active after the signal"),
                    Candidate("until", "keyword", "the signal that stops it"), *_fault_kinds()]
        return _fault_kinds()
    if prev not in (spec.kind, *entry):
        return _fault_kinds()
    given = set(entry)
    out = [Candidate(p.name, "keyword", f"{p.unit}: {p.doc}" + (
        "" if p.default is not None else " (required)"))
           for p in spec.parameters if p.name not in given]
    if "as" not in given and prev == spec.kind:
        out.append(Candidate("as", "keyword", "name this fault"))
    out.extend(Candidate(w, "keyword", "activation") for w in ("from", "to", "when", "until"))
    return out + _fault_kinds()


OBJECT_ROLES = ("static", "dynamic", "human", "robot")


def vepl_completions(text_before: str, names: Iterable[tuple[str, str]]) -> list[Candidate]:
    """Keywords of the VEPL grammar and the (name, kind) pairs its model declares; inside
    ``object[...]``, the roles and catalogue types an object parameter can range over."""
    ctx = context_at(text_before)
    tokens = ctx.previous
    if tokens and tokens[-1] in ("[", ","):
        opening = next((i for i in range(len(tokens) - 1, -1, -1) if tokens[i] in "[]()"), -1)
        if opening > 0 and tokens[opening] == "[" and tokens[opening - 1] == "object":
            roles = [Candidate(role, "keyword", "object role") for role in OBJECT_ROLES]
            return roles + [c for c in _types(None, None) if c.kind == "type"
                            and c.detail not in ("floor", "wall")]
    return _keywords(grammar_keywords("vepl")) + [Candidate(n, kind, kind)
                                                  for n, kind in names]
