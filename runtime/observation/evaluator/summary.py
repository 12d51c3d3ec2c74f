"""The monitor's part of a run summary (thesis 5.2, Tables 5-10): total utility, signal
counts, verdicts and measurements, merged into a RunSummary and written as summary.json.
Never changes what the run itself recorded (outcome, reason, mission, seed)."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from rei.generators.output import write_atomic
from rei.runtime.results import RunSummary, Verdict


@dataclass(frozen=True)
class MonitorResult:
    total_utility: float
    signal_counts: dict[str, int]
    verdicts: tuple[Verdict, ...]
    measurements: dict[str, Any]
    duration: float


def merge_summary(base: RunSummary, result: MonitorResult) -> RunSummary:
    return replace(base, total_utility=result.total_utility,
                   signal_counts=dict(result.signal_counts), verdicts=result.verdicts,
                   measurements={**base.measurements, **result.measurements})


def json_ready(value: Any) -> Any:
    """JSON without NaN/inf: a measurement that never got a value is null."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: json_ready(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_ready(v) for v in value]
    return value


def summary_text(summary: RunSummary) -> str:
    """summary.json's text: sorted keys, no NaN or inf (an unset measurement is null)."""
    return json.dumps(json_ready(summary.to_json()), indent=1, sort_keys=True,
                      allow_nan=False) + "\n"


def write_summary(summary: RunSummary, out_dir: str | Path) -> Path:
    """Write summary.json through a temporary file, so a kill never leaves it torn (and a
    link at its name is replaced, never followed)."""
    path = Path(out_dir) / "summary.json"
    write_atomic(path, summary_text(summary).encode("utf-8"))
    return path
