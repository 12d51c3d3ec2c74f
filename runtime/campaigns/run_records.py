"""The record of one run of a campaign (record.json, written last into the run's folder):
what was planned, how the attempt went, and the run's summary; and why it did not pass, in
words. The results store (``store``) writes and reads them; the tables (``results_table``),
clusters and reports read them. This module must never run a mission or write files.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rei.runtime.campaigns.execute import RunResult
from rei.runtime.campaigns.plan import RunSpec
from rei.runtime.results import RunSummary, RunVerdict, failed_verdicts, judge

RECORD_FORMAT = "rei-run-record"
STORE_VERSION = 1
"""The version of a campaign folder's files (campaign.json and every record.json)."""


@dataclass(frozen=True)
class RunRecord:
    """A recorded run: what was planned, how the attempt went, and the run's summary."""

    spec: RunSpec
    status: str
    exit_code: int | None
    wall_time: float
    message: str
    summary: RunSummary | None

    @property
    def verdict(self) -> RunVerdict:
        """The run's judgement by the one pass rule (rei.runtime.results.judge); a run that
        crashed, hung or left no summary is an error."""
        if self.status != "ran" or self.summary is None:
            return "error"
        return judge(self.summary)

    @property
    def passed(self) -> bool:
        return self.verdict == "pass"

    @property
    def outcome(self) -> str:
        if self.summary is not None:
            return self.summary.outcome
        return "error"

    @property
    def reason(self) -> str:
        if self.summary is not None and self.summary.reason:
            return self.summary.reason
        return self.message

    def to_json(self) -> dict[str, Any]:
        return {"format": RECORD_FORMAT, "version": STORE_VERSION, "spec": self.spec.to_json(),
                "status": self.status, "exit_code": self.exit_code,
                "wall_time": self.wall_time, "message": self.message,
                "summary": self.summary.to_json() if self.summary is not None else None}

    @staticmethod
    def from_json(data: dict[str, Any]) -> RunRecord:
        summary = data.get("summary")
        return RunRecord(spec=RunSpec.from_json(data["spec"]), status=str(data["status"]),
                         exit_code=data.get("exit_code"), wall_time=float(data["wall_time"]),
                         message=str(data.get("message", "")),
                         summary=RunSummary.from_json(summary) if summary else None)

    @staticmethod
    def from_result(spec: RunSpec, result: RunResult) -> RunRecord:
        summary = RunSummary.from_json(result.summary) if result.summary is not None else None
        return RunRecord(spec, result.status, result.exit_code, result.wall_time,
                         result.message, summary)



def verdict_reason(record: RunRecord) -> str:
    """Why the run did not pass, in words ('' when it passed): the first failed (or
    undecided) requirement with its reason, or what broke the run."""
    if record.status != "ran" or record.summary is None:
        return f"{record.status}: {record.message}".strip(": ")
    summary = record.summary
    if summary.outcome in ("error", "interrupted"):
        return f"{summary.outcome}: {summary.reason}"
    blocking = failed_verdicts(summary)
    if blocking:
        first = blocking[0]
        return f"{first.requirement} {first.status}: {first.reason}"
    if not summary.verdicts:
        return "no requirement was checked"
    return ""
