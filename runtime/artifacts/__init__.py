"""Reading the JSON artifacts the generators write for a run (world.json, monitor.json).

One reader for both, so every generated file is refused the same way: unreadable, not JSON,
another format version, or a field that is missing, malformed or not finite — each with the
file, the field, what was expected and what was found. ``world`` reads world.json into
typed records, ``monitor`` reads monitor.json.

A contract at runtime's root: it may import the catalogue, the languages' models, ``messages``
and ``errors``; it must never import pybullet or any wing.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from rei.runtime.errors import RunError


def read_artifact(path: Path, what: str, target: str, version: int) -> dict[str, Any]:
    """The JSON object of a generated artifact of the given format version."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise RunError(f"cannot read the {what} '{path}': {exc.strerror} "
                       f"(generate it with `rei-gen generate --target {target}`)") from None
    except json.JSONDecodeError as exc:
        raise RunError(f"{path}:{exc.lineno}:{exc.colno}: not valid JSON: {exc.msg}") from None
    if not isinstance(data, dict) or data.get("version") != version:
        found = data.get("version") if isinstance(data, dict) else type(data).__name__
        raise RunError(f"{path}: expected {what} version {version}, found {found!r} "
                       f"(generate it again with this REI: `rei-gen generate --target {target}`)")
    return data


def finite(value: Any, where: str) -> float:
    """A finite number from a JSON value; ``where`` is 'file: field'."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise RunError(f"{where}: expected a finite number, found {value!r}")
    return float(value)


SIMULATED_SHAPES = ("box", "cylinder")
"""The footprints the generated world files hold: the shapes the simulator builds
(rei.catalogue.codec.simulated)."""
