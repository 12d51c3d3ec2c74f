"""What a test engineer reads first in a campaign report: the verdict counts, the mission ×
requirement matrix, and the failures grouped into clusters with one representative each.

Everything follows the one pass rule (rei.runtime.results.judge): a run's verdict is its
record's ``verdict``; a requirement's cell counts the runs where it applied. A cluster is
"the same requirement failed on the same kind of object in the same phase of the mission",
so 34 near-identical failures read as three lines. This module must never format HTML; it
reads a run's world.json (roles and types of the objects involved) leniently, because a
crashed run may have left none.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rei.runtime.campaign.stats import by_mission, wilson_interval
from rei.runtime.campaign.store import RunRecord, verdict_reason
from rei.runtime.results import failed_verdicts


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


@dataclass(frozen=True)
class Failure:
    """Why one run did not pass, in words, with what the cluster needs."""

    record: RunRecord
    requirement: str
    """The first failed (or undecided) requirement, or the run's own error."""
    status: str
    time: float | None
    objects: tuple[str, ...]
    kinds: tuple[str, ...]
    """Roles (human, wall, static, dynamic) or catalogue types of the objects involved."""
    phase: str
    reason: str


@dataclass(frozen=True)
class Cluster:
    requirement: str
    kind: str
    phase: str
    failures: tuple[Failure, ...]

    @property
    def missions(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(by_mission(f.record) for f in self.failures))

    @property
    def representative(self) -> Failure:
        return self.failures[0]


def object_kinds(run_dir: Path) -> dict[str, str]:
    """name → role of the run's observed objects (humans by role, objects by type)."""
    try:
        data = json.loads((run_dir / "world" / "world.json").read_text(encoding="utf-8"))
        bodies: list[Any] = [*data.get("walls", ()), *data.get("objects", ())]
        out = {}
        for body in bodies:
            role = str(body.get("role", ""))
            out[str(body["name"])] = role if role in ("wall", "human") else \
                f"{role} {body.get('type', '')}".strip()
        return out
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return {}


def phase_of(record: RunRecord, time: float | None) -> str:
    """The mission's phase at ``time``: the task that ran then, or before / after the tasks."""
    if time is None or record.summary is None:
        return "whole run"
    tasks = record.summary.measurements.get("tasks") or []
    for task in tasks:
        try:
            if float(task["start"]) <= time <= float(task["end"]):
                return f"task {task['index']}: {task['task']}"
        except (KeyError, TypeError, ValueError):
            continue
    if tasks and time < float(tasks[0].get("start", 0.0) or 0.0):
        return "before the first task"
    return "after the tasks" if tasks else "whole run"


def failure_of(record: RunRecord, kinds: dict[str, str]) -> Failure:
    summary = record.summary
    if record.verdict in ("error", "interrupted") or summary is None:
        status = record.verdict
        return Failure(record, "run " + status, status, None, (), (), "whole run",
                       verdict_reason(record))
    blocking = failed_verdicts(summary)
    if not blocking:
        return Failure(record, "no requirement", record.verdict, None, (), (), "whole run",
                       verdict_reason(record))
    first = blocking[0]  # the same one verdict_reason names
    kind_names = tuple(sorted({kinds.get(o, "task" if o.startswith("task") else "object")
                               for o in first.objects}))
    return Failure(record, first.requirement, first.status, first.decided_at, first.objects,
                   kind_names, phase_of(record, first.decided_at), first.reason)


def failures(records: Sequence[RunRecord], run_dir: Any) -> list[Failure]:
    """The failure of every run that did not pass; ``run_dir(record)`` is its folder."""
    out = []
    for record in records:
        if record.passed:
            continue
        kinds = object_kinds(run_dir(record))
        tasks = {str(t.get("task")) for t in (record.summary.measurements.get("tasks") or [])
                 } if record.summary is not None else set()
        kinds.update({t: "task" for t in tasks})
        out.append(failure_of(record, kinds))
    return out


def clusters(found: Sequence[Failure]) -> list[Cluster]:
    """Failures grouped by (requirement, kind of object, phase kind), largest first. The
    phase is compared by its task's position, not its name, so the same goal of different
    rooms clusters together."""
    groups: dict[tuple[str, str, str], list[Failure]] = {}
    for f in found:
        phase = f.phase.split(":")[0]
        groups.setdefault((f.requirement, ", ".join(f.kinds) or "—", phase), []).append(f)
    out = [Cluster(req, kind, phase, tuple(items))
           for (req, kind, phase), items in groups.items()]
    out.sort(key=lambda c: (-len(c.failures), c.requirement, c.kind, c.phase))
    return out
