"""What one run's folder holds, read leniently: its event log (events.csv) as signal events
and its ground-truth paths (from trace.jsonl).

Event logs and traces belong to `rei run`; they are read here leniently, because a crashed
run may have left none or half of them, and a campaign's clusters, its report and a run's
page must still be made. This module must never write files.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np


@dataclass(frozen=True)
class SignalEvent:
    time: float
    signal: str
    utility: float
    total: float


@dataclass(frozen=True)
class Paths:
    """Ground-truth paths of one run, from its trace: robot and each human, (N, 3) t/x/y."""

    robot: np.ndarray
    humans: dict[str, np.ndarray]


def _float(text: str | None) -> float | None:
    try:
        value = float(text) if text not in (None, "") else None
    except ValueError:
        return None
    return value if value is not None and math.isfinite(value) else None


def read_events(run_dir: Path) -> list[SignalEvent]:
    """The run's event log; empty when it has none (crashed) or it cannot be read."""
    path = run_dir / "events.csv"
    try:
        with path.open(newline="", encoding="utf-8") as handle:
            rows = list(csv.DictReader(handle))
    except (OSError, UnicodeDecodeError, csv.Error):
        return []
    events = []
    running = 0.0
    for row in rows:
        time = _float(row.get("time"))
        signal = row.get("signal") or ""
        utility = _float(row.get("utility")) or 0.0
        total = next((_float(row.get(k)) for k in ("total", "total_utility", "running_total")
                      if _float(row.get(k)) is not None), None)
        running = total if total is not None else running + utility
        if time is not None and signal:
            events.append(SignalEvent(time, signal, utility, running))
    return events


def read_paths(run_dir: Path) -> Paths | None:
    """Robot and human paths from the run's trace, when a trace reader is available."""
    try:
        from rei.runtime.trace import read_trace  # noqa: PLC0415
    except ImportError:  # the run stage is not installed with this report: draw without paths
        return None
    for path in (run_dir / "trace.jsonl", run_dir / "trace.jsonl.partial"):
        if not path.is_file():
            continue
        try:
            header, stream = read_trace(path)
            samples = list(stream)
        except Exception:  # noqa: BLE001  (a crashed run's broken trace: draw without it)
            continue
        if not samples:
            continue
        robot = np.array([(s.time, s.robot_pose[0], s.robot_pose[1]) for s in samples])
        humans = {}
        for i, obj in enumerate(header.objects):
            if obj.role == "human":
                humans[obj.name] = np.array([(s.time, s.poses[i, 0], s.poses[i, 1])
                                             for s in samples])
        return Paths(robot, humans)
    return None
