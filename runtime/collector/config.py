"""Reading the `monitor` target's ``monitor.json``: what to observe and how often."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rei.catalogue import Footprint
from rei.runtime.artifacts import footprint, read_artifact
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


def _footprint(data: Any) -> Footprint:
    return footprint(data, "monitor.json: footprint")


def _observed(data: dict[str, Any]) -> ObservedObject:
    return ObservedObject(str(data["name"]), data["role"], str(data["type"]),
                          _footprint(data["footprint"]), float(data["height"]))


def load_monitor_config(folder: str | Path) -> MonitorConfig:
    path = Path(folder) / "monitor.json"
    data = read_artifact(path, "monitor configuration", "monitor", CONFIG_VERSION)
    try:
        rate = float(data["rate"])
        if not (math.isfinite(rate) and rate > 0):
            raise RunError(f"{path}: rate: expected a positive number, found {data['rate']!r}")
        return MonitorConfig(rate, _observed(data["robot"]),
                             tuple(_observed(o) for o in data["objects"]),
                             tuple(str(d) for d in data["data"]), str(data["laser_scans"]))
    except (KeyError, IndexError, TypeError, ValueError) as exc:
        raise RunError(f"{path}: missing or malformed field ({exc})") from None
