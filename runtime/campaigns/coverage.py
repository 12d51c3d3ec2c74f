"""Behaviour coverage of a campaign: which behaviours a navigator owes its runs exercised.

Each run's summary.json holds ``measurements.behaviours`` (rei.runtime.robot.behaviours: what
the controller reported in its feedback and what its commands showed). A campaign sums them:
per behaviour, the runs that exercised it, its episodes and seconds, and which behaviours no
run called for. A behaviour no run exercises is one the suite cannot test; the campaign
report shows the table and ``coverage.json`` holds it. A run without the measurement (an older
summary, a crash) counts as a run with no behaviour, and the coverage says how many such runs
there were. This module must never run a mission.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from rei.runtime.campaigns.run_records import RunRecord
from rei.runtime.robot.behaviours import BEHAVIOURS

COVERAGE_JSON = "coverage.json"


@dataclass(frozen=True)
class BehaviourRow:
    name: str
    meaning: str
    runs: int
    """Runs in which the behaviour ran at least once."""
    episodes: int
    seconds: float


@dataclass(frozen=True)
class Coverage:
    rows: tuple[BehaviourRow, ...]
    """Every known behaviour (BEHAVIOURS' order), then the controllers' own names."""
    runs: int
    """Runs counted (recorded runs)."""
    unmeasured: int
    """Runs whose summary has no behaviour measurement (crashed, or an older summary)."""

    @property
    def never(self) -> tuple[str, ...]:
        """Known behaviours no run exercised."""
        return tuple(r.name for r in self.rows if r.name in BEHAVIOURS and not r.runs)

    @property
    def exercised(self) -> int:
        return sum(1 for r in self.rows if r.name in BEHAVIOURS and r.runs)

    def to_json(self) -> dict[str, Any]:
        return {"runs": self.runs, "unmeasured": self.unmeasured,
                "exercised": self.exercised, "known": len(BEHAVIOURS),
                "never": list(self.never),
                "behaviours": {r.name: {"meaning": r.meaning, "runs": r.runs,
                                        "episodes": r.episodes, "seconds": round(r.seconds, 3)}
                               for r in self.rows}}

    def line(self) -> str:
        """One line for the terminal."""
        text = f"behaviour coverage: {self.exercised} of {len(BEHAVIOURS)} behaviours exercised"
        if self.never:
            text += f"; never: {', '.join(self.never)}"
        return text


def _behaviours_of(record: RunRecord) -> dict[str, Any] | None:
    if record.summary is None:
        return None
    found = record.summary.measurements.get("behaviours")
    return found if isinstance(found, dict) else None


def behaviour_coverage(records: Sequence[RunRecord]) -> Coverage:
    """The campaign's behaviour coverage over ``records``."""
    runs: dict[str, int] = {}
    episodes: dict[str, int] = {}
    seconds: dict[str, float] = {}
    unmeasured = 0
    for record in records:
        found = _behaviours_of(record)
        if found is None:
            unmeasured += 1
            continue
        for name, tally in found.items():
            if not isinstance(tally, dict):
                continue
            runs[name] = runs.get(name, 0) + 1
            episodes[name] = episodes.get(name, 0) + int(tally.get("episodes", 0))
            seconds[name] = seconds.get(name, 0.0) + float(tally.get("seconds", 0.0))
    names = list(BEHAVIOURS) + sorted(set(runs) - set(BEHAVIOURS))
    rows = tuple(BehaviourRow(n, BEHAVIOURS.get(n, "the controller's own behaviour"),
                              runs.get(n, 0), episodes.get(n, 0), seconds.get(n, 0.0))
                 for n in names)
    return Coverage(rows, len(records), unmeasured)


def coverage_json(coverage: Coverage) -> bytes:
    """coverage.json's bytes (sorted keys: the same records give the same bytes)."""
    return (json.dumps({"format": "rei-coverage", "version": 1,
                        **coverage.to_json()}, indent=1, sort_keys=True) + "\n").encode()


__all__ = ["COVERAGE_JSON", "BehaviourRow", "Coverage", "behaviour_coverage", "coverage_json"]
