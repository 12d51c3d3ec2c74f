"""One shrink from a .mission file to an output folder: run the original on every seed, pick
the requirement, shrink, and keep OUT/ always holding the best case so far.

OUT/ gets the smallest failing .mission and .room (rewritten whenever a step improves them,
so an interruption or a spent budget loses nothing), shrink.json (``summary_json``),
before-after.png (the original beside the result, drawn by rei.generators.picture) and
shrink-runs.jsonl (every judged candidate: running the same command again resumes without
rerunning them). This module must never print; ``progress`` gets one line per improvement.
"""

from __future__ import annotations

import shutil
from collections.abc import Callable
from pathlib import Path

from rei.runtime.campaigns.engines import WorkerPool
from rei.runtime.campaigns.shrink.case import ScenarioCase, load_case, sizes
from rei.runtime.campaigns.shrink.oracle import FailureOracle, RunSettings
from rei.runtime.campaigns.shrink.shrinker import (
    JOURNAL,
    PICTURE,
    SUMMARY,
    BudgetSpent,
    Shrinker,
    ShrinkReport,
    choose_requirement,
    replay_command,
    summary_json,
    unknown_requirement,
    write_case_atomically,
    write_json_atomically,
)
from rei.runtime.errors import RunError

WORK = ".shrink-work"
"""Scratch folder inside OUT (candidates and their runs), removed when the shrink ends."""


def shrink_into(mission: Path, out: Path, settings: RunSettings, *,
                requirement: str | None = None, max_runs: int = 200,
                keep: frozenset[str] = frozenset(),
                progress: Callable[[str], None] = lambda line: None) -> ShrinkReport:
    """Shrink ``mission`` into ``out``; the report (also in OUT/shrink.json). LanguageError
    when the mission does not check clean; RunError when ``requirement`` is none of the
    case's (after the original's runs, which are journaled); KeyboardInterrupt after writing
    the best case."""
    case = load_case(mission)
    out.mkdir(parents=True, exist_ok=True)
    # One pool of workers for every candidate, closed however the shrink ends.
    with WorkerPool(settings.workers) as pool:
        oracle = FailureOracle(settings, out / WORK, out / JOURNAL, pool=pool)
        try:
            return _shrink(mission, case, out, oracle, requirement, max_runs, keep, progress)
        finally:
            pool.close()  # before the scratch folder goes: no run may still write there
            shutil.rmtree(out / WORK, ignore_errors=True)
            progress(f"{oracle.started} runs started now, {oracle.runs - oracle.started} "
                     f"remembered from {out / JOURNAL}")


def _shrink(mission: Path, case: ScenarioCase, out: Path, oracle: FailureOracle,
            requirement: str | None, max_runs: int, keep: frozenset[str],
            progress: Callable[[str], None]) -> ShrinkReport:
    before = sizes(case)
    progress(f"running the original on seeds {', '.join(map(str, oracle.settings.seeds))}")
    original = oracle.outcomes(case)
    unknown = unknown_requirement(original, requirement)
    if unknown is not None:
        raise RunError(unknown)
    result, chosen = choose_requirement(original, requirement)
    report = ShrinkReport(str(mission), result, chosen, original, oracle.settings.describe(),
                          before, case)
    files = {"mission": case.mission_name, "room": case.room_name, "picture": PICTURE}
    replay = replay_command(out / case.mission_name, out / "replay",
                            oracle.settings.spec(out / case.mission_name,
                                                 oracle.settings.seeds[0], "replay"))

    def save(best: ScenarioCase) -> None:
        report.best = best
        report.after = sizes(best)
        report.runs = oracle.runs
        write_case_atomically(best, out)
        write_json_atomically(out / SUMMARY, summary_json(report, replay, files))

    if result != "shrunk" or chosen is None:
        report.runs = oracle.runs
        write_json_atomically(out / SUMMARY, summary_json(report, None, {}))
        return report
    save(case)
    shrinker = Shrinker(oracle, chosen, max_runs, keep)

    def better(best: ScenarioCase, what: str) -> None:
        save(best)
        after = report.after
        progress(f"{oracle.runs} runs: {before['elements']} -> {after['elements']} elements "
                 f"({what})")

    shrinker.on_better = better
    try:
        report.best = shrinker.shrink(case, report.steps)
    except BudgetSpent:
        report.stopped = "max-runs"
    except KeyboardInterrupt:
        report.stopped = "interrupted"
        _finish(report, shrinker, oracle, save, mission, out)
        raise
    _finish(report, shrinker, oracle, save, mission, out)
    return report


def _finish(report: ShrinkReport, shrinker: Shrinker, oracle: FailureOracle,
            save: Callable[[ScenarioCase], None], mission: Path, out: Path) -> None:
    report.candidates = shrinker.candidates
    report.rejected_by_check = shrinker.rejected_by_check
    save(report.best)
    if report.stopped != "interrupted":
        draw_before_after(mission, out / report.best.mission_name, report, out / PICTURE)


def draw_before_after(before: Path, after: Path, report: ShrinkReport, target: Path) -> None:
    """The original and the shrunk case side by side (rei.generators.picture's contact
    sheet: the same drawing as `rei-gen show`), as PNG."""
    from rei.generators.picture.render import SheetEntry, render_sheet  # noqa: PLC0415

    entries = [SheetEntry(f"before: {report.before['elements']} elements", before),
               SheetEntry(f"after: {report.after['elements']} elements", after)]
    partial = target.with_name(target.name + ".partial")
    partial.write_bytes(render_sheet(entries, "png"))
    partial.replace(target)


def size_reduction(mission: Path, out: Path, settings: RunSettings, *, max_runs: int = 200,
                   requirement: str | None = None, keep: frozenset[str] = frozenset()
                   ) -> float | None:
    """Shrink ``mission`` into ``out`` and return its size reduction (``reduction.elements``
    of shrink.json: 1 - elements after / before), or None when there was nothing to shrink
    (the case does not fail the requirement on every seed, or its runs broke): the figure
    a benchmark averages over shrunk cases (bench/shrinking.py, bench/search.py)."""
    report = shrink_into(mission, out, settings, requirement=requirement, max_runs=max_runs,
                         keep=keep)
    return report.reduction()["elements"] if report.result == "shrunk" else None
