"""Reading the `monitor` target's ``monitor.json``: what to observe and how often."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rei.lang.mission.model import COLLECTED_DATA, REQUIRED_DATA
from rei.runtime.artifacts import SIMULATED_SHAPES, read_artifact
from rei.runtime.errors import RunError
from rei.runtime.messages import ObservedObject
from rei.runtime.trace.rules import observed_object_of

CONFIG_VERSION = 1


@dataclass(frozen=True)
class MonitorConfig:
    rate: float
    robot: ObservedObject
    objects: tuple[ObservedObject, ...]
    data: tuple[str, ...]
    """What the collector forwards: a subset of COLLECTED_DATA in its order."""
    laser_scans: str
    """'when_new': a sample carries a scan only when a new one was taken since the last."""


def _observed(data: Any, path: Path, field: str) -> ObservedObject:
    # the trace's own rules: one decoding of observed objects for every file that holds them
    return observed_object_of(data, str(path), field, field == "robot", SIMULATED_SHAPES)


def _data(path: Path, value: Any) -> tuple[str, ...]:
    names = value if isinstance(value, list) else None
    if names is None or not all(isinstance(n, str) for n in names) \
            or len(set(names)) != len(names) or not set(names) <= set(COLLECTED_DATA) \
            or not set(REQUIRED_DATA) <= set(names):
        raise RunError(f"{path}: data: expected a list of distinct names of "
                       f"{', '.join(COLLECTED_DATA)} with {', '.join(REQUIRED_DATA)} among "
                       f"them, found {value!r:.200}")
    return tuple(d for d in COLLECTED_DATA if d in names)


def load_monitor_config(folder: str | Path) -> MonitorConfig:
    path = Path(folder) / "monitor.json"
    data = read_artifact(path, "monitor configuration", "monitor", CONFIG_VERSION)
    try:
        rate = float(data["rate"])
        if not (math.isfinite(rate) and rate > 0):
            raise RunError(f"{path}: rate: expected a positive number, found {data['rate']!r}")
        return MonitorConfig(rate, _observed(data["robot"], path, "robot"),
                             tuple(_observed(o, path, f"objects[{i}]")
                                   for i, o in enumerate(data["objects"])),
                             _data(path, data["data"]), str(data["laser_scans"]))
    except (KeyError, IndexError, TypeError, ValueError) as exc:
        raise RunError(f"{path}: missing or malformed field ({exc})") from None
