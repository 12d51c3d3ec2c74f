"""textX metamodels of the REI languages and syntax errors turned into diagnostics.

textX stops at the first syntax error of a file (a PEG parser cannot resynchronise
reliably), so a file has at most one SYNTAX diagnostic; semantic rules run only on files
that parse, and then report every problem at once.
"""

from __future__ import annotations

import functools
import re
from importlib import resources
from typing import Any

from textx import TextXSyntaxError, metamodel_from_file
from textx.metamodel import TextXMetaModel

from rei.lang.errors import Diagnostic, Span
from rei.lang.source import SourceText

LANGUAGES = ("room", "mission", "vepl")
MAX_NESTING_MESSAGE = "the file nests deeper than the parser can follow"


def grammar_path(language: str) -> str:
    return str(resources.files("rei.grammars").joinpath(f"{language}.tx"))


@functools.cache
def metamodel(language: str) -> TextXMetaModel:
    """The metamodel of one REI language (built once per process; metamodels are immutable)."""
    # auto_init_attributes=False keeps an omitted optional number as None, not 0.
    return metamodel_from_file(
        grammar_path(language), auto_init_attributes=False, ignore_case=False, autokwd=True
    )


_TOKEN = re.compile(r"\S{1,30}")


def _found(text: str, line: int, col: int) -> str:
    lines = text.splitlines()
    if line - 1 >= len(lines):
        return "the end of the file"
    rest = lines[line - 1][col - 1 :]
    match = _TOKEN.match(rest.lstrip())
    if match is None:
        # Only white space left on this line: look at what follows.
        tail = "\n".join(lines[line:]).strip()
        if not tail:
            return "the end of the file"
        token = _TOKEN.match(tail)
        return f"'{token.group(0)}'" if token else "the end of the file"
    return f"'{match.group(0)}'"


def _expected(err: TextXSyntaxError) -> str:
    rules = getattr(err, "expected_rules", None) or []
    names: list[str] = []
    for rule in rules:
        rule_name = getattr(rule, "rule_name", "") or ""
        to_match = getattr(rule, "to_match", None)
        if isinstance(to_match, str) and to_match and not rule_name.startswith("__"):
            plain = re.fullmatch(r"[\w{}():=,;\[\]<>.-]+", to_match)
            shown = f"'{to_match}'" if plain else rule_name
        else:
            shown = rule_name or str(rule)
        shown = {"ID": "a name", "STRING": "a quoted string", "Number": "a number",
                 "INT": "a whole number", "EOF": "the end of the file"}.get(shown, shown)
        if shown and shown not in names:
            names.append(shown)
    if not names:
        return "valid syntax"
    if len(names) == 1:
        return names[0]
    return "one of " + ", ".join(names)


def parse(language: str, source: SourceText) -> Any | Diagnostic:
    """The textX model of a source text, or the one syntax diagnostic."""
    mm = metamodel(language)
    try:
        return mm.model_from_str(source.text, file_name=source.path)
    except TextXSyntaxError as err:
        line = err.line or 1
        col = err.col or 1
        return Diagnostic(
            Span(source.path, line, col, line, col + 1),
            "SYNTAX",
            f"expected {_expected(err)}, found {_found(source.text, line, col)}",
        )
    except RecursionError:
        depth, offset = deepest_nesting(source.text)
        line, col = source.line_col(offset)
        return Diagnostic(Span(source.path, line, col, line, col + 1), "SYNTAX-DEPTH",
                          f"expected brackets nested less deeply, found {depth} levels here; "
                          f"{MAX_NESTING_MESSAGE}")


_BRACKETS = re.compile(r'"[^"]*"?|//[^\n]*|/\*(?:[^*]|\*(?!/))*(?:\*/)?|[(\[{]|[)\]}]')
"""Strings and comments (skipped whole) and brackets, the things nesting is made of."""


def deepest_nesting(text: str) -> tuple[int, int]:
    """The deepest bracket nesting of a text and the offset of the bracket that first opens
    it (brackets inside strings and comments do not count): where a SYNTAX-DEPTH points."""
    depth = best = where = 0
    for match in _BRACKETS.finditer(text):
        token = match.group(0)
        if token in "([{":
            depth += 1
            if depth > best:
                best, where = depth, match.start()
        elif token in ")]}":
            depth = max(0, depth - 1)
    return best, where


def span_of(obj: Any, source: SourceText) -> Span:
    """The source region of a textX object."""
    start = getattr(obj, "_tx_position", 0)
    return span_at(source, start, getattr(obj, "_tx_position_end", start))


def span_at(source: SourceText, start: int, end: int) -> Span:
    """The source region between two character offsets."""
    line, col = source.line_col(start)
    end_line, end_col = source.line_col(end)
    return Span(source.path, line, col, end_line, end_col)
