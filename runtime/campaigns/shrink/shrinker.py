"""Shrinking a failing case: stages of delta debugging, each step kept only while the same
requirement still fails on every seed, the best case written as soon as it improves.

Stages, in order: drop humans, dynamic objects, objects and goals (one ddmin over them all),
drop trajectory vertices (straighter, shorter paths), drop grid floors (cells become wall),
round numbers to fewer digits. A candidate that does not check clean is never run. The
outcome is data (``ShrinkReport``); writing it is ``write_outputs``'s. This module must never
print: progress goes to the ``progress`` callback.
"""

from __future__ import annotations

import json
import os
import shlex
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from rei.lang.suggest import did_you_mean
from rei.runtime.campaigns.plan import RunSpec
from rei.runtime.campaigns.shrink.case import (
    ELEMENT_KINDS,
    Element,
    ScenarioCase,
    elements,
    number_sites,
    rounded,
    sizes,
    with_numbers,
    without,
)
from rei.runtime.campaigns.shrink.ddmin import ddmin
from rei.runtime.campaigns.shrink.oracle import FailureOracle, SeedOutcome, fails_everywhere

SHRINK_VERSION = 1
SUMMARY = "shrink.json"
PICTURE = "before-after.png"
JOURNAL = "shrink-runs.jsonl"
STAGES = ("elements", "trajectories", "floors", "numbers")
"""``--keep`` names: what a stage may leave alone. ``elements`` is humans, dynamic objects,
objects, goals and the mission's ``cycles`` (one pass through the goals)."""
_STAGE_KINDS = {"elements": ("humans", "dynamic_objects", "objects", "goals", "cycles"),
                "trajectories": ("trajectory_vertices",), "floors": ("floors",)}

ShrinkResult = Literal["shrunk", "passes", "flaky", "run_error", "invalid_input"]
"""shrunk: the case fails the requirement on every seed and the smallest such case is
written; passes: it fails nothing on any seed (nothing to shrink); flaky: the requirement
fails on some seeds only (nothing is shrunk: a step could not be judged); run_error: a run
of the original case broke; invalid_input: `rei run` refused the original's input (e.g. a
controller it cannot import)."""


class BudgetSpent(Exception):
    """--max-runs reached: shrinking stops with the best case so far."""


@dataclass
class ShrinkReport:
    """What a shrink found; shrink.json is its ``to_json``."""

    mission: str
    result: ShrinkResult
    requirement: str | None
    original: tuple[SeedOutcome, ...]
    settings: dict[str, Any]
    before: dict[str, int]
    best: ScenarioCase
    after: dict[str, int] = field(default_factory=dict)
    steps: list[dict[str, Any]] = field(default_factory=list)
    runs: int = 0
    candidates: int = 0
    rejected_by_check: int = 0
    stopped: str | None = None
    """None: every stage ran to its end; ``max-runs`` or ``interrupted``: the best so far."""

    def reduction(self) -> dict[str, float]:
        """1 - after/before for the element count and the characters (0: nothing removed)."""
        after = self.after or self.before
        return {key: round(1.0 - after[key] / self.before[key], 4) if self.before[key] else 0.0
                for key in ("elements", "characters")}


@dataclass
class Shrinker:
    """Delta debugging of one case against one requirement on the oracle's seeds."""

    oracle: FailureOracle
    requirement: str
    max_runs: int
    keep: frozenset[str] = frozenset()
    on_better: Callable[[ScenarioCase, str], None] = lambda case, what: None
    """Called with each new best case and what the step removed (to write it at once)."""
    candidates: int = 0
    rejected_by_check: int = 0

    def still_fails(self, case: ScenarioCase) -> bool:
        self.candidates += 1
        if case.problems():
            self.rejected_by_check += 1
            return False
        if self.oracle.runs + self.oracle.cost(case) > self.max_runs:
            raise BudgetSpent
        return fails_everywhere(self.oracle.outcomes(case), self.requirement)

    def shrink(self, case: ScenarioCase, steps: list[dict[str, Any]]) -> ScenarioCase:
        """The smallest case found (``steps`` gets one entry per accepted stage); raises
        BudgetSpent or KeyboardInterrupt with the best case already handed to ``on_better``."""
        best = case
        for stage in STAGES:
            if stage in self.keep:
                continue
            if stage == "numbers":
                best = self._numbers(best, steps)
            else:
                best = self._drop(best, stage, steps)
        return best

    def _drop(self, case: ScenarioCase, stage: str, steps: list[dict[str, Any]]) -> ScenarioCase:
        kinds = _STAGE_KINDS[stage]
        items = [e for e in elements(case) if e.kind in kinds]
        best = [case]

        def fails(kept: list[Element]) -> bool:
            gone = [e for e in items if e not in kept]
            candidate = without(case, gone)
            if candidate.digest() == best[0].digest():
                return True
            if not self.still_fails(candidate):
                return False
            best[0] = candidate
            self.on_better(candidate, f"{stage}: dropped {_labels(gone)}")
            return True

        kept = ddmin(items, fails)
        removed = [e for e in items if e not in kept]
        if removed:
            steps.append({"stage": stage, "removed": [_described(e) for e in removed]})
        return best[0]

    def _numbers(self, case: ScenarioCase, steps: list[dict[str, Any]]) -> ScenarioCase:
        sites = [(s, rounded(s.text)) for s in number_sites(case)]
        sites = [(s, options) for s, options in sites if options]
        if not sites:
            return case
        changes: list[dict[str, str]] = []
        every = with_numbers(case, [(s, options[0]) for s, options in sites])
        if self.still_fails(every):
            self.on_better(every, "numbers: rounded every number")
            steps.append({"stage": "numbers", "rounded": [
                {"from": s.text, "to": options[0]} for s, options in sites]})
            return every
        best = case
        # one at a time, from the last so the earlier offsets stay valid
        for site, options in sorted(sites, key=lambda x: (x[0].file, -x[0].start)):
            for option in options:
                candidate = with_numbers(best, [(site, option)])
                if self.still_fails(candidate):
                    best = candidate
                    self.on_better(best, f"numbers: {site.text} -> {option}")
                    changes.append({"from": site.text, "to": option})
                    break
        if changes:
            steps.append({"stage": "numbers", "rounded": changes})
        return best


def _described(element: Element) -> str:
    """``human pacer``, ``floor hall_2_4``; goals and vertices say what they are already."""
    noun = {"humans": "human", "dynamic_objects": "dynamic object", "objects": "object",
            "floors": "floor"}.get(element.kind)
    return f"{noun} {element.label}" if noun else element.label


def _labels(gone: Sequence[Element]) -> str:
    names = [e.label for e in gone]
    return ", ".join(names[:4]) + (f" and {len(names) - 4} more" if len(names) > 4 else "")


def unknown_requirement(outcomes: Sequence[SeedOutcome], wanted: str | None) -> str | None:
    """Why ``wanted`` (--requirement) names no requirement of the case, in one line, or None:
    None too when no run judged anything (a broken run, or a journal without the names)."""
    judged = list(dict.fromkeys(r for o in outcomes for r in o.judged))
    if wanted is None or not judged or wanted in judged:
        return None
    return (f"--requirement: expected one of the requirements the case's runs judged "
            f"({', '.join(judged)}), found '{wanted}'{did_you_mean(wanted, judged)}")


def choose_requirement(outcomes: Sequence[SeedOutcome], wanted: str | None
                       ) -> tuple[ShrinkResult, str | None]:
    """The requirement to keep failing and what the original case does: ``wanted`` (or the
    first requirement the first seed failed that every seed failed) when it fails on every
    seed; else passes, flaky or run_error."""
    if any(o.verdict == "invalid" for o in outcomes):
        return "invalid_input", wanted
    if any(o.verdict == "error" for o in outcomes):
        return "run_error", wanted
    failed_somewhere = [r for o in outcomes for r in o.failed]
    candidates = [wanted] if wanted is not None else list(dict.fromkeys(failed_somewhere))
    for requirement in candidates:
        if fails_everywhere(outcomes, requirement):
            return "shrunk", requirement
    wanted_somewhere = failed_somewhere if wanted is None else \
        [r for r in failed_somewhere if r == wanted]
    if wanted_somewhere:
        return "flaky", wanted if wanted is not None else wanted_somewhere[0]
    return "passes", wanted


def replay_command(mission: Path, output: Path, spec_like: RunSpec) -> str:
    """The one `rei run` command that replays the shrunk case on its first seed."""
    argv = RunSpec(run_id="replay", mission_file=str(mission), mission_key="", group="",
                   repeat=0, seed=spec_like.seed, controller=spec_like.controller,
                   vepl=spec_like.vepl, duration=spec_like.duration,
                   variation=spec_like.variation, functions=spec_like.functions,
                   vepl_parameters=spec_like.vepl_parameters).run_argv(str(output))
    return shlex.join(["rei", *argv])


def summary_json(report: ShrinkReport, replay: str | None, files: dict[str, str]
                 ) -> dict[str, Any]:
    """shrink.json: a function of the inputs, seeds and version (no clock, no host)."""
    return {
        "version": SHRINK_VERSION,
        "mission": report.mission,
        # where `rei report` matches a shrink to a campaign's runs
        # (rei.runtime.campaigns.failure_clusters)
        "mission_file": str(Path(report.mission).resolve()),
        "result": report.result,
        "requirement": report.requirement,
        "complete": report.stopped is None,
        "stopped": report.stopped,
        "run": report.settings,
        "original": [o.to_json() for o in report.original],
        "sizes": {"before": report.before, "after": report.after or report.before},
        "reduction": report.reduction(),
        "steps": report.steps,
        "runs": report.runs,
        "candidates": report.candidates,
        "rejected_by_check": report.rejected_by_check,
        "files": files,
        "replay": replay,
    }


def write_json_atomically(path: Path, data: dict[str, Any]) -> None:
    """Write ``data`` so that a reader (or an interruption) never sees half a file."""
    partial = path.with_name(path.name + ".partial")
    partial.write_text(json.dumps(data, indent=2, sort_keys=True) + "\n", encoding="utf-8")
    os.replace(partial, path)


def write_case_atomically(case: ScenarioCase, folder: Path) -> Path:
    """Write the case's two files into ``folder``, each replaced whole; the mission's path."""
    for name, text in ((case.room_name, case.room_text), (case.mission_name, case.mission_text)):
        partial = folder / (name + ".partial")
        partial.write_text(text, encoding="utf-8")
        os.replace(partial, folder / name)
    return folder / case.mission_name


__all__ = ["ELEMENT_KINDS", "JOURNAL", "PICTURE", "STAGES", "SUMMARY", "BudgetSpent",
           "ShrinkReport", "Shrinker", "choose_requirement", "replay_command", "sizes",
           "summary_json", "unknown_requirement", "write_case_atomically", "write_json_atomically"]
