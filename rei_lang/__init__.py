"""REI's languages: .room, .mission (and .vepl), their checks, and the command line.

Public API::

    Workspace        check and load files (rooms imported by missions are read once)
    load_room        a valid RoomDocument, or LanguageError with every diagnostic
    load_mission     a valid MissionDocument (with its room), or LanguageError
    Diagnostic       FILE:LINE:COL: RULE-ID: message
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version
from typing import Any

try:
    __version__ = version("rei-testbed")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"

_EXPORTS = {"Workspace": "rei.lang.workspace", "load_room": "rei.lang.workspace",
            "load_mission": "rei.lang.workspace", "Diagnostic": "rei.lang.errors"}

__all__ = ["Diagnostic", "Workspace", "__version__", "load_mission", "load_room"]


def __getattr__(name: str) -> Any:
    # Imported when first asked for: every `rei` command imports this package, and textX's
    # metamodels are heavy; a command that never parses a file never pays for them.
    if name in _EXPORTS:
        import importlib  # noqa: PLC0415

        return getattr(importlib.import_module(_EXPORTS[name]), name)
    raise AttributeError(f"module 'rei.lang' has no attribute '{name}'")
