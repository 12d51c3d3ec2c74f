"""Reading the `monitor` target's ``monitor.json``: what to observe and how often."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rei.catalogue import Box, Cylinder, Footprint
from rei.runtime.errors import RunError
from rei.runtime.messages import ObservedObject

CONFIG_VERSION = 1


@dataclass(frozen=True)
class MonitorConfig:
    rate: float
    robot: ObservedObject
    objects: tuple[ObservedObject, ...]
    data: tuple[str, ...]
    laser_scans: str
    """'when_new': a sample carries a scan only when a new one was taken since the last."""


def _footprint(data: dict[str, Any]) -> Footprint:
    if data["shape"] == "cylinder":
        return Cylinder(float(data["radius"]))
    return Box(float(data["size"][0]), float(data["size"][1]))


def _observed(data: dict[str, Any]) -> ObservedObject:
    return ObservedObject(str(data["name"]), data["role"], str(data["type"]),
                          _footprint(data["footprint"]), float(data["height"]))


def load_monitor_config(folder: str | Path) -> MonitorConfig:
    path = Path(folder) / "monitor.json"
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise RunError(f"cannot read the monitor configuration '{path}': {exc.strerror} "
                       f"(generate it with `rei-gen generate --target monitor`)") from None
    except json.JSONDecodeError as exc:
        raise RunError(f"{path}:{exc.lineno}:{exc.colno}: not valid JSON: {exc.msg}") from None
    if data.get("version") != CONFIG_VERSION:
        raise RunError(f"{path}: expected monitor configuration version {CONFIG_VERSION}, found "
                       f"{data.get('version')!r}")
    try:
        rate = float(data["rate"])
        if not (math.isfinite(rate) and rate > 0):
            raise RunError(f"{path}: rate: expected a positive number, found {data['rate']!r}")
        return MonitorConfig(rate, _observed(data["robot"]),
                             tuple(_observed(o) for o in data["objects"]),
                             tuple(str(d) for d in data["data"]), str(data["laser_scans"]))
    except (KeyError, IndexError, TypeError, ValueError) as exc:
        raise RunError(f"{path}: missing or malformed field ({exc})") from None
