"""One .vepl file analysed end to end: parse, link, check; the entry point of rei-gen check.

``check_vepl`` is what rei.lang.workspace calls for .vepl files; ``load_vepl`` raises
LanguageError with every problem. This module must never import the runtime.
"""

from __future__ import annotations

import functools
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

from rei.lang.errors import Diagnostic, LanguageError, sorted_diagnostics
from rei.lang.parsing import parse
from rei.lang.source import SourceText, read_source
from rei.lang.vepl.linker import link_vepl
from rei.lang.vepl.model import Specification
from rei.lang.vepl_parameters import ParameterValues, parameter_values

if TYPE_CHECKING:
    from rei.lang.workspace import Workspace

DEFAULT_VEPL = Path(str(resources.files("rei.lang.vepl").joinpath("default.vepl")))
"""The default specification: thesis Table 3 utilities, appendix 9.2.2 patterns, 5.1.2
requirements."""


@dataclass(frozen=True)
class VeplDocument:
    source: SourceText | None
    spec: Specification | None
    diagnostics: tuple[Diagnostic, ...]

    @property
    def ok(self) -> bool:
        return self.spec is not None and not any(d.is_error for d in self.diagnostics)


def analyse_vepl(source: SourceText | Diagnostic,
                 overrides: ParameterValues = ()) -> VeplDocument:
    """The document of ``source`` with ``overrides`` (``--param``) in place of the file's
    parameter values."""
    if isinstance(source, Diagnostic):
        return VeplDocument(None, None, (source,))
    return _analysed(source.path, source.text, overrides)


@functools.lru_cache(maxsize=8)
def _analysed(path: str, text: str, overrides: ParameterValues) -> VeplDocument:
    """The analysis of one text, made once: a run reads its specification five times (the
    automata's generator, the monitor, the user functions, the data check), and the result
    depends on nothing but the path, the text and the overrides (a document of frozen
    records)."""
    source = SourceText(path, text)
    parsed = parse("vepl", source)
    if isinstance(parsed, Diagnostic):
        return VeplDocument(source, None, (parsed,))
    spec, diagnostics = link_vepl(parsed, source, overrides)
    return VeplDocument(source, spec, tuple(sorted_diagnostics(diagnostics)))


def check_vepl(workspace: Workspace, path: str | Path) -> list[Diagnostic]:
    return list(analyse_vepl(workspace.source(path)).diagnostics)


def load_vepl(path: str | Path | None = None,
              overrides: Iterable[tuple[str, float]] | Mapping[str, float] | None = None
              ) -> Specification:
    """A valid specification (the default one when ``path`` is None), with ``overrides``
    (``--param NAME=VALUE``) in place of the file's parameter values; raises LanguageError
    (an override of a parameter the file does not declare too)."""
    doc = analyse_vepl(read_source(path if path is not None else DEFAULT_VEPL),
                       parameter_values(overrides))
    if not doc.ok or doc.spec is None:
        raise LanguageError([d for d in doc.diagnostics if d.is_error])
    return doc.spec


def changed_parameters(path: str | Path | None,
                       overrides: Iterable[tuple[str, float]] | Mapping[str, float] | None
                       ) -> ParameterValues:
    """The overrides whose value is not the file's (what a result must say it was judged
    against beyond the file); raises LanguageError like ``load_vepl``."""
    values = parameter_values(overrides)
    if not values:
        return ()
    load_vepl(path, values)  # every name declared, every rule kept
    file = load_vepl(path).parameters
    return tuple((name, value) for name, value in values if file[name] != value)
