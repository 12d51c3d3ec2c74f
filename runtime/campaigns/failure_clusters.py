"""Failure clusters: a campaign's failed runs as a handful of distinct failures, each with its
smallest reproducer and the one command that replays it (what the report shows first, and
clusters.json).

A cluster is "the same requirement failed on the same kind of object in the same phase of the
mission, after the same few signals": (requirement, kinds of the objects the deciding event
involved, phase = which task by position, or before / after the tasks, the last
``LEAD_SIGNALS`` distinct signals of the event log up to the decision). Its reproducer is the
failing run whose mission is smallest (fewest humans, objects, goals, floors and trajectory
vertices: rei.runtime.campaigns.shrink.case.sizes), shortest run next; when `rei shrink` wrote a
result
for that requirement and one of the cluster's missions into ``DIR/shrunk/NAME/``, the shrunk
case is the reproducer and its replay command the one shown. Everything is a function of the
campaign folder's files and the mission files its runs name: the same inputs give the same
clusters, byte for byte. This module
must never format HTML; it reads run folders (world.json, events.csv) leniently, because a
crashed run may have left none.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rei.runtime.campaigns.run_records import RunRecord, verdict_reason
from rei.runtime.campaigns.stats import by_mission
from rei.runtime.observation.run_folder import read_events
from rei.runtime.results import failed_verdicts

LEAD_SIGNALS = 3
"""How many signals before a failure tell its story (consecutive repeats count once)."""
SHRUNK = "shrunk"
"""Folder of a campaign where `rei shrink ... -o DIR/shrunk/NAME` results are looked for."""
CLUSTERS_JSON = "clusters.json"
CLUSTERS_VERSION = 1


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
    lead: tuple[str, ...] = ()
    """The last signals up to the failure (consecutive repeats once), oldest first."""


@dataclass(frozen=True)
class Reproducer:
    """The smallest case that shows a cluster's failure, and how to replay it."""

    failure: Failure
    size: int | None
    """Elements of its case (None: the mission file could not be read)."""
    replay: str
    shrunk: str | None = None
    """The shrunk .mission (relative to the campaign folder) when `rei shrink` made one."""


@dataclass(frozen=True)
class Cluster:
    requirement: str
    status: str
    """How its runs ended on the requirement (fail, inconclusive, ...): never mixed, so the
    reproducer's replay shows the cluster's failure."""
    kind: str
    phase: str
    lead: tuple[str, ...]
    failures: tuple[Failure, ...]
    reproducer: Reproducer | None = None

    @property
    def missions(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(by_mission(f.record) for f in self.failures))

    @property
    def representative(self) -> Failure:
        return self.reproducer.failure if self.reproducer is not None else self.failures[0]


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


def lead_of(run_dir: Path, time: float | None) -> tuple[str, ...]:
    """The last ``LEAD_SIGNALS`` signals of the run's event log up to ``time`` (the whole log
    when the verdict was decided at the end), consecutive repeats once."""
    names: list[str] = []
    for event in read_events(run_dir):
        if time is not None and event.time > time + 1e-9:
            break
        if not names or names[-1] != event.signal:
            names.append(event.signal)
    return tuple(names[-LEAD_SIGNALS:])


def failure_of(record: RunRecord, kinds: dict[str, str], run_dir: Path | None = None
               ) -> Failure:
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
    lead = lead_of(run_dir, first.decided_at) if run_dir is not None else ()
    return Failure(record, first.requirement, first.status, first.decided_at, first.objects,
                   kind_names, phase_of(record, first.decided_at), first.reason, lead)


def failures(records: Sequence[RunRecord], run_dir: Callable[[RunRecord], Path]
             ) -> list[Failure]:
    """The failure of every run that did not pass; ``run_dir(record)`` is its folder."""
    out = []
    for record in records:
        if record.passed:
            continue
        folder = run_dir(record)
        kinds = object_kinds(folder)
        tasks = {str(t.get("task")) for t in (record.summary.measurements.get("tasks") or [])
                 } if record.summary is not None else set()
        kinds.update({t: "task" for t in tasks})
        out.append(failure_of(record, kinds, folder))
    return out


def clusters(found: Sequence[Failure], rerun: Mapping[str, str] | None = None,
             root: Path | None = None) -> list[Cluster]:
    """Failures grouped by (requirement, its status, kind of object, phase kind, lead-up
    signals), largest first. The phase is compared by its task's position, not its name, so
    the same goal of different rooms clusters together. With ``rerun`` (run id → its `rei
    run` command) each cluster gets its smallest reproducer; with ``root`` (the campaign
    folder) shrink results in ``root/shrunk/`` are used."""
    groups: dict[tuple[str, str, str, str, tuple[str, ...]], list[Failure]] = {}
    for f in found:
        phase = f.phase.split(":")[0]
        groups.setdefault((f.requirement, f.status, ", ".join(f.kinds) or "—", phase, f.lead),
                          []).append(f)
    shrunk = shrink_results(root) if root is not None else []
    sizes: dict[str, int | None] = {}
    out = []
    for (req, status, kind, phase, lead), items in groups.items():
        reproducer = None
        if rerun is not None:
            reproducer = smallest_reproducer(items, rerun, sizes, shrunk)
        out.append(Cluster(req, status, kind, phase, lead, tuple(items), reproducer))
    out.sort(key=lambda c: (-len(c.failures), c.requirement, c.status, c.kind, c.phase,
                            c.lead))
    return out


def case_size(mission_file: str, cache: dict[str, int | None]) -> int | None:
    """Elements of the case of a .mission (None when it does not check clean any more)."""
    if mission_file not in cache:
        from rei.lang.errors import LanguageError  # noqa: PLC0415
        from rei.runtime.campaigns.shrink.case import load_case, sizes  # noqa: PLC0415

        try:
            cache[mission_file] = sizes(load_case(Path(mission_file)))["elements"]
        except (LanguageError, OSError):
            cache[mission_file] = None
    return cache[mission_file]


@dataclass(frozen=True)
class ShrinkResult:
    """A `rei shrink` result found in a campaign folder."""

    mission_file: str
    requirement: str
    mission: str
    """The shrunk .mission, relative to the campaign folder."""
    size: int
    replay: str


def shrink_results(root: Path) -> list[ShrinkResult]:
    """The successful shrinks under ``root/shrunk/*/shrink.json``, in folder order; files that
    are not one (or a shrink that found nothing) are left out."""
    out = []
    folder = root / SHRUNK
    for summary in sorted(folder.glob("*/shrink.json")) if folder.is_dir() else ():
        try:
            data = json.loads(summary.read_text(encoding="utf-8"))
            if data.get("result") != "shrunk":
                continue
            mission = summary.parent / str(data["files"]["mission"])
            out.append(ShrinkResult(str(data["mission_file"]), str(data["requirement"]),
                                    mission.relative_to(root).as_posix(),
                                    int(data["sizes"]["after"]["elements"]),
                                    str(data["replay"])))
        except (OSError, ValueError, KeyError, TypeError, AttributeError):
            continue
    return out


def smallest_reproducer(items: Sequence[Failure], rerun: Mapping[str, str],
                        sizes: dict[str, int | None], shrunk: Sequence[ShrinkResult]
                        ) -> Reproducer:
    """The failure of ``items`` with the smallest case (then the shortest run, then the run
    id); a shrink of one of their missions for the same failed requirement beats every run
    (a shrunk case fails it: no reproducer of an inconclusive one)."""
    missions = {f.record.spec.mission_file for f in items}
    for result in shrunk if items[0].status == "fail" else ():
        if result.mission_file in missions and result.requirement == items[0].requirement:
            failure = next(f for f in items if f.record.spec.mission_file == result.mission_file)
            return Reproducer(failure, result.size, result.replay, result.mission)

    def key(f: Failure) -> tuple[float, float, str]:
        size = case_size(f.record.spec.mission_file, sizes)
        duration = f.record.summary.duration if f.record.summary is not None else 0.0
        return (size if size is not None else float("inf"), duration, f.record.spec.run_id)

    best = min(items, key=key)
    return Reproducer(best, case_size(best.record.spec.mission_file, sizes),
                      rerun.get(best.record.spec.run_id, ""))


def clusters_json(found: Sequence[Cluster]) -> dict[str, Any]:
    """clusters.json: every cluster with its runs and its reproducer."""
    return {"version": CLUSTERS_VERSION, "clusters": [
        {"requirement": c.requirement, "status": c.status, "objects": c.kind, "phase": c.phase,
         "lead": list(c.lead), "runs": [f.record.spec.run_id for f in c.failures],
         "missions": list(c.missions),
         "reproducer": None if c.reproducer is None else {
             "run": c.reproducer.failure.record.spec.run_id,
             "mission": c.reproducer.shrunk or c.reproducer.failure.record.spec.mission_key,
             "shrunk": c.reproducer.shrunk is not None,
             "elements": c.reproducer.size,
             "time": c.reproducer.failure.time,
             "reason": c.reproducer.failure.reason,
             "replay": c.reproducer.replay}}
        for c in found]}
