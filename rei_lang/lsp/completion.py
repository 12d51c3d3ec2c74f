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
from rei.lang.mission.faults import KINDS
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
TRAJECTORY_OPTIONS = ("total", "loop", "stop", "when")
"""What may follow ``trajectory`` before its ``{``."""
TRIGGER_NEXT = {"when": "robot", "robot": "within"}
"""A start trigger (``when robot within D of FLOOR``) word by word."""


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
def _grammar_texts(language: str) -> tuple[str, ...]:
    """The texts of a language's grammar and of the grammars it imports, comments removed."""
    texts: list[str] = []
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
        texts.append(text)
        pending.extend(re.findall(r"^\s*import\s+(\w+)", text, re.MULTILINE))
    return tuple(texts)


@functools.cache
def grammar_keywords(language: str) -> tuple[str, ...]:
    """Every keyword of a language's grammar (and the grammars it imports)."""
    words: set[str] = set()
    for text in _grammar_texts(language):
        words.update(re.findall(r"'([A-Za-z_]\w*)'", text))
    return tuple(sorted(words))


@functools.cache
def _rules(language: str) -> dict[str, str]:
    """Rule name -> rule body, over a language's grammar and its imports."""
    rules: dict[str, str] = {}
    for text in _grammar_texts(language):
        for name, body in re.findall(r"^(\w+):\s*(.*?)^;", text, re.MULTILINE | re.DOTALL):
            rules.setdefault(name, " ".join(body.split()))
    return rules


def _first_keywords(language: str, rule: str) -> tuple[str, ...]:
    """The words that can open a rule: its leading keyword, or those of a choice's rules."""
    body = _rules(language).get(rule, "")
    leading = re.match(r"(?:\w+=)?'(\w+)'", body)
    if leading:
        return (leading.group(1),)
    if re.fullmatch(r"\w+(?:\s*\|\s*\w+)*", body):
        return tuple(w for alternative in body.split("|")
                     for w in _first_keywords(language, alternative.strip()))
    return ()


@functools.cache
def statement_keywords(language: str, choice: str) -> tuple[str, ...]:
    """The words that start a statement of a block whose items are the choice rule
    ``choice`` (``RoomItem``, ``MissionItem``)."""
    return _first_keywords(language, choice)


@dataclass(frozen=True)
class Clause:
    """One optional clause that may follow a placement's floor (``offset DX DY``,
    ``heading D``, ``trajectory ... { }``, a goal's ``tolerance M``...)."""
    keywords: tuple[str, ...]
    """The words that open it (several for a choice such as a goal's options)."""
    values: int
    """How many values follow its keyword."""
    block: bool
    """It ends with a ``{ }`` block (a trajectory)."""
    repeats: bool


@dataclass(frozen=True)
class Placement:
    """What the grammar says of a statement that puts something on a floor."""
    head: re.Pattern[str]
    """Matches the statement's tokens (space-joined) before its placement word."""
    word: str
    """``on`` (room bodies) or ``at`` (goals); empty for a trajectory vertex."""
    clauses: tuple[Clause, ...]
    """The optional clauses after the floor, in grammar order."""


_PLACED = re.compile(r"(?:'(on|at)'\s+)?floor=Ref\b")
_HEAD_ITEM = re.compile(r"'([^']+)'|\w+=\w+|\(|\)\??|\S+")
_TAIL_ITEM = re.compile(r"\(\s*'(\w+)'([^)]*)\)([?*])|\w+([*+]?)=(\w+)(\?)?")


def _values(body: str) -> int:
    return len(re.findall(r"\w+=(?:Number|ID|STRING|Ref)\b", body))


def _clauses(language: str, rule: str) -> tuple[Clause, ...]:
    body = _rules(language).get(rule, "")
    alternatives = [a.strip() for a in body.split("|")]
    if len(alternatives) > 1 and all(re.fullmatch(r"\w+", a) for a in alternatives):
        return tuple(c for a in alternatives for c in _clauses(language, a))
    words = _first_keywords(language, rule)
    if not words:
        return ()
    return (Clause(words, _values(body), "'{'" in body, False),)


@functools.cache
def placement(language: str, rule: str) -> Placement | None:
    """The placement of a statement rule (``StaticObject``, ``Goal``, ``Vertex``...) read from
    the grammar, so completion offers a clause exactly where the grammar accepts it."""
    body = _rules(language).get(rule, "")
    placed = _PLACED.search(body)
    if placed is None:
        return None
    pattern = ""
    for item in _HEAD_ITEM.finditer(body[:placed.start()]):
        text = item.group(0)
        if item.group(1) is not None:
            pattern += re.escape(item.group(1)) + " "
        elif "=" in text:
            pattern += r"\w+ "
        elif text == "(":
            pattern += "(?:"
        elif text.startswith(")"):
            pattern += ")" + text[1:]
    clauses: list[Clause] = []
    for item in _TAIL_ITEM.finditer(body[placed.end():]):
        keyword, group, group_mark, many, target, _ = item.groups()
        if keyword is not None:
            clauses.append(Clause((keyword,), _values(group), False, group_mark == "*"))
            continue
        for clause in _clauses(language, target):
            clauses.append(Clause(clause.keywords, clause.values, clause.block, many == "*"
                                  or clause.repeats))
    return Placement(re.compile(pattern), placed.group(1) or "", tuple(clauses))


def _rule_of_statement(language: str, choice: str, keyword: str) -> str | None:
    body = _rules(language).get(choice, "")
    return next((rule.strip() for rule in body.split("|")
                 if keyword in _first_keywords(language, rule.strip())), None)


@dataclass(frozen=True)
class Following:
    """What may come next inside a statement."""
    words: tuple[str, ...]
    """Its own keywords accepted here."""
    complete: bool
    """The statement may end here (a new one may start)."""


def clauses_after(tokens: tuple[str, ...], clauses: tuple[Clause, ...]) -> Following | None:
    """What may come after ``tokens``, the clauses that followed a placement's floor: the
    clauses not yet given (a repeating one again), nothing while a clause still waits for its
    values; None when the tokens are not clauses of this placement."""
    position = 0
    i = 0
    while i < len(tokens):
        found = next((j for j in range(position, len(clauses))
                      if tokens[i] in clauses[j].keywords), None)
        if found is None:
            return None
        clause = clauses[found]
        if clause.block:
            if "{}" not in tokens[i:]:
                return Following((), False)
            i = tokens.index("{}", i) + 1
        else:
            i += 1 + clause.values
            if i > len(tokens):
                return Following((), False)
        position = found if clause.repeats else found + 1
    return Following(tuple(w for clause in clauses[position:] for w in clause.keywords), True)


def _placement_following(language: str, choice: str, statement: tuple[str, ...]
                         ) -> Following:
    """Inside a statement (``statement`` starts with its keyword): the placement word once
    the head is complete, then the clauses the grammar still accepts."""
    rule = _rule_of_statement(language, choice, statement[0])
    place = placement(language, rule) if rule else None
    if place is None:
        return Following((), len(statement) > 1)  # its name or value follows the keyword
    if place.word not in statement:
        joined = "".join(f"{t} " for t in statement)
        return Following((place.word,) if place.head.fullmatch(joined) else (), False)
    after = statement[statement.index(place.word) + 2:]
    return clauses_after(after, place.clauses) or Following((), True)


def _vertex_following(level: tuple[str, ...]) -> Following:
    """Inside a trajectory (``level``: its vertices so far): after a vertex's floor, its
    clauses (``offset``, ``at``) still accepted; a new vertex's floor where one may start."""
    place = placement("room", "Vertex")
    if place is None or not level:
        return Following((), True)
    start = 0
    i = 0
    while i < len(level):
        clause = next((c for c in place.clauses if level[i] in c.keywords), None)
        if clause is None:
            start = i  # a vertex's floor
            i += 1
        else:
            i += 1 + clause.values
    return clauses_after(level[start + 1:], place.clauses) or Following((), True)


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
    level: tuple[str, ...] = ()
    """The tokens of the innermost block at its own depth, a nested block as one ``{}``."""


def context_at(text_before: str) -> Context:
    text = text_before[-LOOKBEHIND_CHARS:]
    partial = _WORD_END.search(text)
    if partial is not None:
        text = text[:partial.start()]
    tokens = [t for t in _TOKEN.findall(text) if not t.startswith(("//", "/*"))]
    blocks: list[str] = []
    levels: list[list[str]] = [[]]
    for i, token in enumerate(tokens):
        if token == "{":
            opener = next((t for t in reversed(tokens[max(0, i - 12):i]) if t in BLOCK_OPENERS
                           or t == "{" or t == "}"), "")
            blocks.append(opener if opener in BLOCK_OPENERS else "")
            levels.append([])
        elif token == "}" and blocks:
            blocks.pop()
            levels.pop()
            levels[-1].append("{}")
        else:
            levels[-1].append(token)
    return Context(tuple(tokens[-12:]), tuple(blocks), tuple(levels[-1]))


def current_statement(level: tuple[str, ...], starters: tuple[str, ...]) -> tuple[str, ...]:
    """The tokens of the statement the cursor is in: from the last word that starts one."""
    start = max((i for i, t in enumerate(level) if t in starters), default=None)
    return () if start is None else level[start:]


def _statement_completions(language: str, choice: str, level: tuple[str, ...]
                           ) -> list[Candidate]:
    """In a block of statements: the clauses the grammar still accepts in the current one,
    then, where it may end, the words that start a new statement."""
    starters = statement_keywords(language, choice)
    statement = current_statement(level, starters)
    if not statement:
        return _keywords(starters)
    following = _placement_following(language, choice, statement)
    return _keywords(following.words) + (_keywords(starters) if following.complete else [])


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
        following = _vertex_following(ctx.level)
        return _keywords(following.words) + (_floors(room) if following.complete else [])
    if block == "floor":
        return _keywords(SIDES)
    if block == "legend":
        if prev == "=":
            return _keywords(("floor", "wall", "empty"))
        return []
    if block == "grid":
        return _keywords(("legend",))
    if block == "room":
        return _statement_completions("room", "RoomItem", ctx.level)
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
        return _statement_completions("mission", "MissionItem", ctx.level)
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
