"""The record of one run, as the evaluator writes it to summary.json and campaigns read it.

Verdicts are data: a failed requirement is a ``Verdict`` with ``status == "fail"``, never an
exception. This module must never import pybullet.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any, Literal

RESULTS_VERSION = 1

Outcome = Literal["completed", "failed", "timeout", "error", "interrupted"]
"""completed: every task ended (succeeded or failed) in time; failed: a task failed;
timeout: the mission's time limit ran out; error: the run itself broke (controller raised,
hung or sent non-finite commands); interrupted: stopped by the user (output incomplete)."""

VerdictStatus = Literal["pass", "fail", "inconclusive"]


@dataclass(frozen=True)
class Verdict:
    requirement: str
    status: VerdictStatus
    decided_at: float | None
    """Simulation time of the event that decided it (None when decided at the end)."""
    reason: str


@dataclass(frozen=True)
class RunSummary:
    version: int
    mission: str
    room: str
    seed: int
    controller: str
    outcome: Outcome
    reason: str
    duration: float
    """Simulation seconds."""
    total_utility: float
    signal_counts: dict[str, int]
    verdicts: tuple[Verdict, ...]
    measurements: dict[str, Any] = field(default_factory=dict)
    """min_distance_to_human, path_length, time_to_goal per task, sample problems, ..."""

    def to_json(self) -> dict[str, Any]:
        data = asdict(self)
        data["verdicts"] = [asdict(v) for v in self.verdicts]
        return data

    @staticmethod
    def from_json(data: dict[str, Any]) -> RunSummary:
        verdicts = tuple(Verdict(**v) for v in data.get("verdicts", ()))
        fields = {k: v for k, v in data.items() if k != "verdicts"}
        return RunSummary(verdicts=verdicts, **fields)

    @property
    def passed(self) -> bool:
        return all(v.status == "pass" for v in self.verdicts) and self.outcome != "error"
