"""The self-contained HTML report of a campaign (report.html): no external files.

Top to bottom: the verdict counts and the pass rule, the failures grouped into clusters (each
with its smallest reproducer and replay command: rei.runtime.campaigns.failure_clusters), the
mission ×
requirement matrix, one collapsed section per mission with each run's verdict,
reason, re-run command and (for failed runs) its map, then the thesis's tables and plots. One
small inline script sorts the matrix; the page reads fine without it.

Plots are inline SVG, maps PNG data URIs, the style sheet is inlined, so the page can be
attached to a CI job or mailed. Rendered with jinja2 (autoescaped). This module must never
write files.
"""

from __future__ import annotations

import math
import os
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from urllib.parse import quote

import jinja2

from rei.runtime.campaigns.coverage import Coverage
from rei.runtime.campaigns.failure_clusters import Cluster, clusters, failures
from rei.runtime.campaigns.folder_reader import CampaignData
from rei.runtime.campaigns.run_records import RunRecord, verdict_reason
from rei.runtime.campaigns.stats import (
    by_mission,
    campaign_outcome,
    campaign_passed,
    classify_pairs,
    mission_verdicts,
)
from rei.runtime.campaigns.store import RUNS, required_pass_rate
from rei.runtime.observation.run_folder import read_events
from rei.runtime.presentation.campaign_report import campaign_plots as plots
from rei.runtime.presentation.campaign_report.overview import requirement_matrix
from rei.runtime.presentation.campaign_report.tables import (
    coverage_table,
    execution_summary,
    group_success_table,
    mission_success,
    signal_counts,
    success_table,
)
from rei.runtime.presentation.run_page.rendering import PAGE, page_is_full
from rei.runtime.presentation.templating import environment

MAX_MAPS = 40
"""Failed runs drawn from above (each ~40 kB of PNG); the rest are listed without a map."""



def run_page_link(root: Path, record: RunRecord) -> str | None:
    """The href of a recorded run's page relative to the campaign folder's report.html, or
    None when the run folder has none (the run crashed, or ran with --no-monitor)."""
    page = Path(root) / RUNS / record.spec.run_id / PAGE
    if not page.is_file():
        return None
    return quote(Path(os.path.relpath(page, root)).as_posix())

def _number(value: object) -> str:
    if value is None:
        return "–"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        if not math.isfinite(value):
            return "–"
        if value.is_integer() and abs(value) < 1e9:
            return str(int(value))
        return f"{value:.4g}" if abs(value) < 1000 else f"{value:.1f}"
    return str(value)


def _setting(value: object) -> str:
    """A provenance value as a reader would write it: the engine ``{"engine": "local",
    "workers": 2}`` as "local (workers 2)", a list joined, a number as ``_number``."""
    if isinstance(value, dict):
        name = value.get("engine", value.get("name"))
        rest = ", ".join(f"{k} {_setting(v)}" for k, v in value.items()
                         if k not in ("engine", "name"))
        if name is not None and rest:
            return f"{name} ({rest})"
        return str(name) if name is not None else (rest or "–")
    if isinstance(value, (list, tuple)):
        return ", ".join(_setting(v) for v in value) or "–"
    return _number(value)


ROTATE_AFTER = 4
"""Requirements in the matrix beyond which their headers stand rotated (one narrow column
each) instead of wrapping at underscores."""


def _environment() -> jinja2.Environment:
    env = environment()
    env.filters["num"] = _number
    env.filters["setting"] = _setting
    env.filters["pct"] = lambda v: f"{100 * v:.0f} %"
    env.globals["ROTATE_AFTER"] = ROTATE_AFTER
    return env


@dataclass(frozen=True)
class MissionSection:
    name: str
    runs: tuple[RunRecord, ...]
    passed: int
    flaky: bool
    open: bool
    """Failed missions start open when there are few, so the page stays short."""
    verdict: str
    """pass / fail / flaky against the required pass rate; 'static twin' for --pair-static."""
    why: str
    pair: str
    """With --pair-static: 'fails with people only', 'fails in the static room too', ..."""


def render_html(data: CampaignData, rerun: dict[str, str], coverage: Coverage,
                situations: Coverage, found: list[Cluster] | None = None) -> str:
    """The page; ``coverage`` and ``situations``: the campaign's behaviour and situation
    coverage; ``found``: the clusters (worked out here when not given)."""
    records = list(data.records)
    failed = [r for r in records if not r.passed]
    missions = mission_success(records)
    tables = [execution_summary(records)]
    if len({r.spec.group for r in records}) > 1:
        tables.append(execution_summary(records, key=lambda r: r.spec.group,
                                        label="Group"))
    maps = {}
    for record in failed[:MAX_MAPS]:
        image = plots.failure_map(data, record)
        if image:
            maps[record.spec.run_id] = image
    runs_of: dict[str, list[RunRecord]] = {}
    for record in records:
        runs_of.setdefault(by_mission(record), []).append(record)
    rates = {m.key: m for m in missions}
    required = required_pass_rate(data.manifest)
    judged = {v.mission: v for v in mission_verdicts(records, required)}
    pairs = {p.mission: p.cause for p in classify_pairs(records)}
    few = sum(1 for m in missions if m.passed < m.runs) <= 3

    def section(name: str, runs: list[RunRecord]) -> MissionSection:
        rate = rates[name]
        mv = judged.get(name)
        return MissionSection(name, tuple(runs), rate.passed, rate.flaky,
                              few and rate.passed < rate.runs,
                              mv.verdict if mv is not None else "static twin",
                              mv.reason if mv is not None else "the room without its people "
                              "and moving objects (--pair-static); not judged",
                              pairs.get(name, ""))
    sections = [section(name, runs) for name, runs in
                sorted(runs_of.items(), key=lambda kv: (rates[kv[0]].rate, kv[0]))]
    verdicts = Counter(r.verdict for r in records)
    not_applicable = sum(v.status == "not_applicable" for r in records if r.summary
                         for v in r.summary.verdicts)
    css = resources.files("rei.runtime.presentation").joinpath("templates/report.css").read_text(
        encoding="utf-8")
    mission_count = len(runs_of)
    return _environment().get_template("report.html.j2").render(
        title=f"REI campaign: {mission_count} mission{'s' if mission_count != 1 else ''} × "
              f"{data.plan.repeat} repeat{'s' if data.plan.repeat != 1 else ''}",
        folder=data.root.name, css=css,
        planned=len(data.plan.runs), recorded=len(records), passed=verdicts["pass"],
        campaign_pass=campaign_passed(judged.values()) and len(records) == len(data.plan.runs),
        campaign_status=campaign_outcome(records, judged.values(),
                                         planned=len(data.plan.runs)).status,
        required=required, mission_counts=Counter(v.verdict for v in judged.values()),
        counts={"fail": verdicts["fail"], "inconclusive": verdicts["inconclusive"],
                "error": verdicts["error"] + verdicts["interrupted"]},
        not_applicable=not_applicable,
        flaky=[m for m in missions if m.flaky],
        repeat=data.plan.repeat, seed=data.plan.seed,
        matrix=requirement_matrix(records),
        clusters=found if found is not None else clusters(failures(failed, data.run_dir),
                                                          rerun, data.root),
        missions=sections, rerun=rerun, reason_of=verdict_reason,
        page_of=lambda record: run_page_link(data.root, record),
        pages=page_counts(data.root, records),
        success_tables=[success_table(missions, "Mission"), group_success_table(records)],
        summary_tables=tables, signal_table=signal_counts(records),
        coverage=coverage, coverage_table=coverage_table(coverage),
        situations=situations, situation_table=coverage_table(situations),
        utility_plot=plots.utility_over_time(data),
        signal_plot=plots.signal_distribution(records),
        descriptor_plot=plots.success_by_descriptor(records),
        utilities=utility_legend(data),
        maps=maps, more_maps=max(0, len(failed) - MAX_MAPS),
        provenance=data.manifest.get("sessions", []),
        # what the runs were judged against beyond the .vepl file (`--param`)
        parameters=sorted({(name, value) for r in records if r.summary is not None
                           for name, value in r.summary.parameters.items()}),
    )


def page_counts(root: Path, records: Sequence[RunRecord]) -> dict[str, int]:
    """How many recorded runs have a brief page (``--pages failed``: a run that passed) and
    how many no page (``--pages none``, a run that crashed): what the report says of its
    links."""
    counts = {"brief": 0, "missing": 0}
    for record in records:
        if run_page_link(root, record) is None:
            counts["missing"] += 1
        elif not page_is_full(root / RUNS / record.spec.run_id):
            counts["brief"] += 1
    return counts


def utility_legend(data: CampaignData) -> list[tuple[str, float]]:
    """(signal, utility) of every signal seen in the campaign's event logs."""
    seen: dict[str, float] = {}
    for record in data.records:
        if record.summary is None or set(record.summary.signal_counts) <= set(seen):
            continue
        for event in read_events(data.run_dir(record)):
            seen.setdefault(event.signal, event.utility)
    return sorted(seen.items())
