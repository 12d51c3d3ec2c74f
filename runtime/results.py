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

VerdictStatus = Literal["pass", "fail", "inconclusive", "not_applicable"]
"""not_applicable: the requirement's premise (``when QUERY`` in the .vepl: people in the room,
a back-and-forth mission, goals with headings) never held in the run, so it judged nothing."""

RunVerdict = Literal["pass", "fail", "inconclusive", "error", "interrupted", "unjudged"]
"""The run's one judgement (``judge``): pass, fail (a requirement failed), inconclusive (none
failed but one could not be decided), error (the run itself broke), interrupted (stopped by
the user), unjudged (no requirement was checked: ``rei run --no-monitor``)."""


PAGE_POLICIES = ("all", "failed", "none")
"""Which runs get their page, report.html (`rei run --page`, `rei campaign --pages`): ``all``
the full page; ``failed`` the full page for a run that did not pass, a brief one (verdicts,
no plots or map) for a run that did; ``none`` no page. Here, not in
rei.runtime.presentation.campaign_report, so
that the commands' parsers need not import the report's libraries."""

@dataclass(frozen=True)
class Verdict:
    requirement: str
    status: VerdictStatus
    decided_at: float | None
    """Simulation time of the event that decided it (None when decided at the end)."""
    reason: str
    objects: tuple[str, ...] = ()
    """What the deciding event involved: objects, humans or tasks (names)."""
    margin: float | None = None
    """How far the run was from failing it (rei.runtime.observation.evaluator.margins): negative
    exactly
    when it failed; None when the requirement has no natural margin, or for an inconclusive
    or not-applicable verdict."""
    margin_unit: str = ""
    margin_note: str = ""
    """Why a margin was withheld, when one was worked out but disagreed with the verdict."""


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
    parameters: dict[str, float] = field(default_factory=dict)
    """The specification's parameters set with `--param` to a value other than the file's:
    what the verdicts were judged against beyond the .vepl (summary.json leaves it out when
    empty, so a run without overrides writes what it always did)."""

    def to_json(self) -> dict[str, Any]:
        data = asdict(self)
        if not self.parameters:
            del data["parameters"]
        data["verdicts"] = [{**asdict(v), "objects": list(v.objects)} for v in self.verdicts]
        data["verdict"] = judge(self)
        return data

    @staticmethod
    def from_json(data: dict[str, Any]) -> RunSummary:
        verdicts = tuple(Verdict(**{**v, "objects": tuple(v.get("objects", ()))})
                         for v in data.get("verdicts", ()))
        fields = {k: v for k, v in data.items() if k not in ("verdicts", "verdict")}
        return RunSummary(verdicts=verdicts, **fields)

    @property
    def verdict(self) -> RunVerdict:
        return judge(self)

    @property
    def passed(self) -> bool:
        return judge(self) == "pass"


def judge(summary: RunSummary) -> RunVerdict:
    """The one pass rule behind every exit status, JUnit file, results table and report.

    A run passes exactly when it ran to its end and every applicable requirement passed.
    Task outcomes (aborted, timed out, false success claims), speed, headings and collisions
    reach the verdict only through requirements of the .vepl, never through a side rule here.
    """
    if summary.outcome == "error":
        return "error"
    if summary.outcome == "interrupted":
        return "interrupted"
    statuses = {v.status for v in summary.verdicts}
    if not statuses:
        return "unjudged"
    if "fail" in statuses:
        return "fail"
    if "inconclusive" in statuses:
        return "inconclusive"
    if statuses == {"not_applicable"}:
        # nothing was judged: a specification whose every premise is absent proves nothing
        return "inconclusive"
    return "pass"


def failed_verdicts(summary: RunSummary) -> tuple[Verdict, ...]:
    """The verdicts that keep the run from passing: failures before inconclusive ones, each
    the earliest decided first (decided at the end: last); the first is *the* reason."""
    order = {"fail": 0, "inconclusive": 1}
    return tuple(sorted((v for v in summary.verdicts if v.status in order),
                        key=lambda v: (order[v.status], v.decided_at is None,
                                       v.decided_at or 0.0)))
