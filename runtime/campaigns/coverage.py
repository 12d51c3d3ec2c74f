"""Coverage of a campaign: which behaviours a navigator owes its runs exercised, and which
situations the world put the robot in.

Each run's summary.json holds ``measurements.behaviours`` (rei.runtime.robot.behaviours: what
the controller reported in its feedback and what its commands showed) and
``measurements.situations`` (rei.runtime.observation.model.situations: what the ground truth
shows). A campaign sums each: per name, the runs in which it occurred, its episodes and
seconds, and which known names no run met. A behaviour no run exercises, or a situation no run
meets, is one the suite cannot test; the campaign report shows the tables and
``coverage.json`` holds them. A run without the measurement (an older summary, a crash)
counts as a run with none, and the coverage says how many such runs there were. This module
must never run a mission.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from rei.runtime.campaigns.run_records import RunRecord
from rei.runtime.observation.model.situations import SITUATIONS
from rei.runtime.robot.behaviours import BEHAVIOURS

COVERAGE_JSON = "coverage.json"


@dataclass(frozen=True)
class CoverageRow:
    name: str
    meaning: str
    runs: int
    """Runs in which it occurred at least once."""
    episodes: int
    seconds: float


@dataclass(frozen=True)
class Coverage:
    what: str
    """'behaviours' or 'situations' (the summary's measurement, and the words shown)."""
    known: dict[str, str]
    """The known names and what they mean (BEHAVIOURS, SITUATIONS)."""
    rows: tuple[CoverageRow, ...]
    """Every known name in the vocabulary's order, then any other name the runs gave (a
    controller's own behaviours)."""
    runs: int
    """Runs counted (recorded runs)."""
    unmeasured: int
    """Runs whose summary has no behaviour measurement (crashed, or an older summary)."""

    @property
    def never(self) -> tuple[str, ...]:
        """Known names no run met."""
        return tuple(r.name for r in self.rows if r.name in self.known and not r.runs)

    @property
    def exercised(self) -> int:
        """Known names some run met."""
        return sum(1 for r in self.rows if r.name in self.known and r.runs)

    def to_json(self) -> dict[str, Any]:
        return {"runs": self.runs, "unmeasured": self.unmeasured,
                "exercised": self.exercised, "known": len(self.known),
                "never": list(self.never),
                "rows": {r.name: {"meaning": r.meaning, "runs": r.runs,
                                     "episodes": r.episodes, "seconds": round(r.seconds, 3)}
                         for r in self.rows}}

    def line(self) -> str:
        """One line for the terminal."""
        singular = self.what[:-1]
        verb = "exercised" if self.what == "behaviours" else "met"
        text = (f"{singular} coverage: {self.exercised} of {len(self.known)} {self.what} "
                f"{verb}")
        if self.never:
            text += f"; never: {', '.join(self.never)}"
        return text


def _measured(record: RunRecord, what: str) -> dict[str, Any] | None:
    if record.summary is None:
        return None
    found = record.summary.measurements.get(what)
    return found if isinstance(found, dict) else None


def behaviour_coverage(records: Sequence[RunRecord]) -> Coverage:
    """The campaign's behaviour coverage over ``records``."""
    return _coverage(records, "behaviours", BEHAVIOURS, "the controller's own behaviour")


def situation_coverage(records: Sequence[RunRecord]) -> Coverage:
    """The campaign's situation coverage over ``records``."""
    return _coverage(records, "situations", SITUATIONS, "")


def _coverage(records: Sequence[RunRecord], what: str, known: dict[str, str],
              other: str) -> Coverage:
    runs: dict[str, int] = {}
    episodes: dict[str, int] = {}
    seconds: dict[str, float] = {}
    unmeasured = 0
    for record in records:
        found = _measured(record, what)
        if found is None:
            unmeasured += 1
            continue
        for name, tally in found.items():
            if not isinstance(tally, dict):
                continue
            runs[name] = runs.get(name, 0) + 1
            episodes[name] = episodes.get(name, 0) + int(tally.get("episodes", 0))
            seconds[name] = seconds.get(name, 0.0) + float(tally.get("seconds", 0.0))
    names = list(known) + sorted(set(runs) - set(known))
    rows = tuple(CoverageRow(n, known.get(n, other), runs.get(n, 0), episodes.get(n, 0),
                             seconds.get(n, 0.0))
                 for n in names)
    return Coverage(what, known, rows, len(records), unmeasured)


def coverage_json(behaviours: Coverage, situations: Coverage) -> bytes:
    """coverage.json's bytes: both coverages (sorted keys: the same records, the same bytes)."""
    data = {"format": "rei-coverage", "version": 1,
            "behaviours": behaviours.to_json(), "situations": situations.to_json()}
    return (json.dumps(data, indent=1, sort_keys=True) + "\n").encode()


__all__ = ["COVERAGE_JSON", "Coverage", "CoverageRow", "behaviour_coverage", "coverage_json",
           "situation_coverage"]
