"""Editor support for .vepl files: outline, names to complete, and where a name is declared.

The VEPL language (rei.lang.vepl) is optional for the server: it is imported lazily and
read by attribute, so a missing or changed module degrades to keywords only, never to an
error. Diagnostics of .vepl files come from ``Workspace.check`` like every other kind; this
module must never check a rule.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Iterator
from typing import Any

from rei.lang.errors import Diagnostic, Span
from rei.lang.lsp.navigation import Found, Place, Written, name_span
from rei.lang.lsp.outline import Symbol
from rei.lang.lsp.positions import LineIndex
from rei.lang.source import SourceText

log = logging.getLogger("rei.lsp")

# (attribute of the specification, outline kind, what to call it in a hover)
_SECTIONS = (("queries", "query", "query"), ("query_events", "event", "query event"),
             ("complex_events", "event", "complex event"), ("signals", "signal", "signal"),
             ("requirements", "requirement", "requirement"))


def analyse(source: SourceText | Diagnostic) -> Any:
    """The VEPL document of a source (None when the VEPL language is not installed)."""
    try:
        from rei.lang.vepl.document import analyse_vepl
    except ImportError:
        return None
    return analyse_vepl(source)


def specification(document: Any) -> Any:
    return getattr(document, "spec", None)


def declarations(document: Any) -> Iterator[tuple[str, str, str, Any]]:
    """(section kind, hover name, name, declaration record) of every named declaration."""
    spec = specification(document)
    if spec is None:
        return
    for attribute, kind, shown in _SECTIONS:
        for decl in getattr(spec, attribute, None) or ():
            name = getattr(decl, "name", None)
            if isinstance(name, str) and isinstance(getattr(decl, "span", None), Span):
                yield kind, shown, name, decl


def outline(document: Any, index: LineIndex) -> list[Symbol]:
    out = []
    for kind, shown, name, decl in declarations(document):
        out.append(Symbol(name, kind, shown, decl.span, name_span(index, decl.span, name)))
    return sorted(out, key=lambda s: (s.span.line, s.span.col))


def completion_names(document: Any) -> list[tuple[str, str]]:
    """(name, kind) of the queries and events a specification declares."""
    spec = specification(document)
    names: list[tuple[str, str]] = []
    for kind, _, name, _ in declarations(document):
        if kind in ("query", "event", "signal"):
            names.append((name, "query" if kind == "query" else "event"))
    for name in getattr(spec, "parameters", None) or {}:
        names.append((name, "parameter"))
    return names


def find(document: Any, index: LineIndex, line: int, col: int) -> Found | None:
    """The declared name under the cursor (a query, event, signal or requirement)."""
    text = index.line_text(line)
    for match in re.finditer(r"[A-Za-z_]\w*", text):
        if match.start() + 1 <= col <= match.end() + 1:
            word = match.group(0)
            break
    else:
        return None
    source = getattr(document, "source", None)
    path = getattr(source, "path", "")
    written = Written(Span(path, line, match.start() + 1, line, match.end() + 1), "block", word)
    for _, shown, name, decl in declarations(document):
        if name == word:
            first_line = index.line_text(decl.span.line).strip()
            place = Place(decl.span.file, name_span(index, decl.span, name),
                          getattr(source, "text", None))
            return Found(written, place, f"**{shown}** `{name}`\n\n```\n{first_line}\n```")
    spec = specification(document)
    parameters = getattr(spec, "parameters", None) or {}
    if word in parameters:
        return Found(written, None, f"**parameter** `{word}` = {parameters[word]:g}")
    return None
