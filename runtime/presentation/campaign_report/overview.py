"""The mission × requirement matrix of a campaign report (the failure clusters that lead the
report are rei.runtime.campaigns.failure_clusters).

Everything follows the one pass rule (rei.runtime.results.judge): a run's verdict is its
record's ``verdict``; a requirement's cell counts the runs where it applied. This module must
never format HTML.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

# The failure clusters lived here before they led the report; their home is
# rei.runtime.campaigns.failure_clusters, and these names stay importable from here for existing
# callers.
from rei.runtime.campaigns.failure_clusters import Cluster, Failure, clusters, failures
from rei.runtime.campaigns.run_records import RunRecord
from rei.runtime.campaigns.stats import by_mission, wilson_interval


@dataclass(frozen=True)
class Cell:
    """One requirement in one mission, over the mission's runs."""

    applicable: int
    passed: int
    failed: int
    inconclusive: int
    low: float
    high: float
    """Wilson 95 % interval of the pass rate over the runs where it applied."""

    @property
    def rate(self) -> float | None:
        return self.passed / self.applicable if self.applicable else None

    @property
    def css(self) -> str:
        if not self.applicable:
            return "na"
        if self.passed == self.applicable:
            return "good"
        return "bad" if self.passed == 0 else "mixed"


@dataclass(frozen=True)
class MissionRow:
    mission: str
    runs: int
    passed: int
    cells: tuple[Cell | None, ...]
    """Aligned with Matrix.requirements; None where the mission's runs never checked it."""


@dataclass(frozen=True)
class Matrix:
    requirements: tuple[str, ...]
    rows: tuple[MissionRow, ...]


def requirement_matrix(records: Sequence[RunRecord]) -> Matrix:
    """Missions × requirements; rows worst first (lowest pass rate), then by name."""
    names: list[str] = []
    by_mission_runs: dict[str, list[RunRecord]] = {}
    for record in records:
        by_mission_runs.setdefault(by_mission(record), []).append(record)
        for v in record.summary.verdicts if record.summary is not None else ():
            if v.requirement not in names:
                names.append(v.requirement)
    rows = []
    for mission, runs in by_mission_runs.items():
        cells: list[Cell | None] = []
        for name in names:
            found = [v for r in runs for v in (r.summary.verdicts if r.summary else ())
                     if v.requirement == name]
            if not found:
                cells.append(None)
                continue
            applicable = [v for v in found if v.status != "not_applicable"]
            passed = sum(v.status == "pass" for v in applicable)
            low, high = wilson_interval(passed, len(applicable))
            cells.append(Cell(len(applicable), passed,
                              sum(v.status == "fail" for v in applicable),
                              sum(v.status == "inconclusive" for v in applicable), low, high))
        rows.append(MissionRow(mission, len(runs), sum(r.passed for r in runs), tuple(cells)))
    rows.sort(key=lambda r: (r.passed / r.runs if r.runs else 0.0, r.mission))
    return Matrix(tuple(names), tuple(rows))



__all__ = ["Cell", "Cluster", "Failure", "Matrix", "MissionRow", "clusters", "failures",
           "requirement_matrix"]
