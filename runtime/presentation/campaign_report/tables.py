"""The summary tables of a campaign, shaped like the thesis's (Tables 5–10).

Execution summary per room or preset (Table 5/7 shape): executions, mean and median execution
time, mean / median / max / min utility, and a Total row; signal counts per room (Table 6/8
shape); success rates with Wilson intervals per mission and per group. Tables are records of
strings and numbers; this module must never format HTML or read files.
"""

from __future__ import annotations

import statistics
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from rei.runtime.campaigns.coverage import Coverage
from rei.runtime.campaigns.run_records import RunRecord
from rei.runtime.campaigns.stats import SuccessRate, by_group, by_mission, success_rates
from rei.runtime.presentation.signals import SIGNAL_ORDER


@dataclass(frozen=True)
class Table:
    title: str
    columns: tuple[str, ...]
    rows: tuple[tuple[object, ...], ...]
    footer: tuple[object, ...] | None = None


def room_key(records: Sequence[RunRecord]) -> Callable[[RunRecord], str]:
    """Group by room; a run without a summary (crashed) joins its mission's room when known."""
    rooms = {r.spec.mission_file: r.summary.room for r in records
             if r.summary is not None and r.summary.room}

    def key(record: RunRecord) -> str:
        if record.summary is not None and record.summary.room:
            return record.summary.room
        return rooms.get(record.spec.mission_file) or str(
            record.spec.parameters.get("room") or record.spec.mission_key)
    return key


def execution_summary(records: Sequence[RunRecord],
                      key: Callable[[RunRecord], str] | None = None,
                      label: str = "Room") -> Table:
    """Thesis Table 5: per key, executions, execution time and utility statistics."""
    key = key or room_key(records)
    groups: dict[str, list[RunRecord]] = {}
    for record in records:
        groups.setdefault(key(record), []).append(record)

    def row(name: str, runs: list[RunRecord]) -> tuple[object, ...]:
        times = [r.summary.duration for r in runs if r.summary is not None]
        utils = [r.summary.total_utility for r in runs if r.summary is not None]
        if not times:
            return (name, len(runs), None, None, None, None, None, None)
        return (name, len(runs), statistics.fmean(times), statistics.median(times),
                statistics.fmean(utils), statistics.median(utils), max(utils), min(utils))

    rows = tuple(row(name, runs) for name, runs in sorted(groups.items()))
    return Table(f"Execution summary per {label.lower()}",
                 (label, "Executions", "Mean execution time [s]", "Median execution time [s]",
                  "Mean utility", "Median utility", "Max utility", "Min utility"),
                 rows, row("Total", list(records)) if records else None)


def signal_counts(records: Sequence[RunRecord],
                  key: Callable[[RunRecord], str] | None = None) -> Table:
    """Thesis Table 6: one row per signal, one column per room, summed over its runs."""
    key = key or room_key(records)
    keys = sorted({key(r) for r in records})
    counts: dict[str, dict[str, int]] = {}
    for record in records:
        if record.summary is None:
            continue
        for signal, count in record.summary.signal_counts.items():
            column = counts.setdefault(signal, {})
            column[key(record)] = column.get(key(record), 0) + count
    order = [s for s in SIGNAL_ORDER if s in counts] + sorted(set(counts) - set(SIGNAL_ORDER))
    rows = tuple((s, *(counts[s].get(k, 0) for k in keys), sum(counts[s].values()))
                 for s in order)
    return Table("Signals captured per room", ("Signal", *keys, "Total"), rows)


def success_table(rates: Sequence[SuccessRate], label: str) -> Table:
    """Per mission: the rate over its repeats, labelled flaky when the repeats disagree."""
    rows = tuple((r.key, r.runs, r.passed, _pct(r.rate), f"[{_pct(r.low)}, {_pct(r.high)}]",
                  _repeats(r)) for r in rates)
    return Table(f"Success rate per {label.lower()} (Wilson 95 % interval)",
                 (label, "Runs", "Passed", "Success rate", "95 % interval", "Repeats"), rows)


def _repeats(rate: SuccessRate) -> str:
    """What the repeats of a mission say together (the column is never left empty)."""
    if rate.runs <= 1:
        return "one run"
    if rate.flaky:
        return "flaky"  # the template marks exactly this word
    if rate.passed == rate.runs:
        return "all passed"
    if rate.passed == 0:
        return "none passed"
    return "disagree"


def _pct(value: float) -> str:
    return f"{100 * value:.0f} %"


def group_success_table(records: Sequence[RunRecord]) -> Table:
    """Per group: the rate over all its runs, and how many of its missions are flaky (a group
    of different missions that disagree is not flaky; its missions' repeats may be)."""
    flaky: dict[str, int] = {}
    mission_group = {by_mission(r): r.spec.group for r in records}
    for rate in mission_success(records):
        if rate.flaky:
            group = mission_group[rate.key]
            flaky[group] = flaky.get(group, 0) + 1
    rows = tuple((r.key, r.runs, r.passed, _pct(r.rate), f"[{_pct(r.low)}, {_pct(r.high)}]",
                  flaky.get(r.key, 0)) for r in group_success(records))
    return Table("Success rate per group (Wilson 95 % interval)",
                 ("Group", "Runs", "Passed", "Success rate", "95 % interval",
                  "Flaky missions"), rows)


def mission_success(records: Sequence[RunRecord]) -> list[SuccessRate]:
    return success_rates(records, by_mission)


def group_success(records: Sequence[RunRecord]) -> list[SuccessRate]:
    return success_rates(records, by_group)


def coverage_table(coverage: Coverage) -> Table:
    """A coverage: one row per behaviour (or situation), the runs it occurred in and how
    much."""
    rows = tuple((r.name, r.meaning, r.runs, r.episodes, round(r.seconds, 1))
                 for r in coverage.rows)
    return Table(f"{coverage.what.capitalize()} per campaign",
                 (coverage.what[:-1].capitalize(), "Meaning", "Runs", "Episodes", "Seconds"),
                 rows)
