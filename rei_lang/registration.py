"""Registration of the REI languages with textX (`textx list-languages`, `textx check`).

The registered metamodels run REI's full semantic checks as a model processor, so
`textx check` reports the same rules as `rei-gen check` (textX shows the first one).
"""

from __future__ import annotations

from typing import Any

from textx import LanguageDesc, TextXSemanticError, metamodel_from_file

from rei.lang.parsing import grammar_path
from rei.lang.workspace import Workspace


def _semantic_processor(model: Any, metamodel: Any) -> None:
    path = getattr(model, "_tx_filename", None)
    if not path:
        return  # a model parsed from a string has no file to check against its room
    errors = [d for d in Workspace().check(path) if d.is_error]
    if errors:
        first = errors[0]
        more = ""
        if len(errors) > 1:
            more = f" (and {len(errors) - 1} more; run `rei-gen check` for all)"
        raise TextXSemanticError(f"{first.rule}: {first.message}{more}", line=first.span.line,
                                 col=first.span.col, filename=first.span.file)


def _registered_metamodel(language: str) -> Any:
    mm = metamodel_from_file(grammar_path(language), auto_init_attributes=False, autokwd=True)
    mm.register_model_processor(_semantic_processor)
    return mm


room_language = LanguageDesc(
    "rei-room", pattern="*.room",
    description="REI context model: floors, walls, objects, humans and a robot",
    metamodel=lambda: _registered_metamodel("room"))

vepl_language = LanguageDesc(
    "rei-vepl", pattern="*.vepl",
    description="REI monitoring specification: queries, event patterns, signals, requirements",
    metamodel=lambda: _registered_metamodel("vepl"))

mission_language = LanguageDesc(
    "rei-mission", pattern="*.mission",
    description="REI mission: an ordered list of navigation goals in a room",
    metamodel=lambda: _registered_metamodel("mission"))
