"""The self-contained HTML report of a campaign (report.html): no scripts, no external files.

Plots are inline SVG, maps PNG data URIs, the style sheet is inlined, so the page can be
attached to a CI job or mailed. Rendered with jinja2 (autoescaped). This module must never
write files.
"""

from __future__ import annotations

import math
from importlib import resources

import jinja2

from rei.runtime.campaign.stats import by_mission
from rei.runtime.campaign.store import verdict_reason
from rei.runtime.report import plots
from rei.runtime.report.data import CampaignData
from rei.runtime.report.run_page import run_page_link
from rei.runtime.report.tables import (
    execution_summary,
    group_success_table,
    mission_success,
    signal_counts,
    success_table,
)

MAX_MAPS = 40
"""Failed runs drawn from above (each ~40 kB of PNG); the rest are listed without a map."""
MAX_FAILURES = 200
"""Failures listed in full; the rest are in junit.xml and results.csv."""


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


def _environment() -> jinja2.Environment:
    env = jinja2.Environment(
        loader=jinja2.PackageLoader("rei.runtime.report", "templates"),
        autoescape=jinja2.select_autoescape(["html", "j2"], default=True),
        undefined=jinja2.StrictUndefined, trim_blocks=True, lstrip_blocks=True)
    env.filters["num"] = _number
    env.filters["pct"] = lambda v: f"{100 * v:.0f} %"
    return env


def render_html(data: CampaignData, rerun: dict[str, str]) -> str:
    records = list(data.records)
    failures = [r for r in records if not r.passed]
    missions = mission_success(records)
    tables = [execution_summary(records)]
    if len({r.spec.group for r in records}) > 1:
        tables.append(execution_summary(records, key=lambda r: r.spec.group,
                                        label="Group"))
    maps = []
    for record in failures[:MAX_MAPS]:
        image = plots.failure_map(data, record)
        maps.append((record, image))
    passed = sum(r.passed for r in records)
    css = resources.files("rei.runtime.report").joinpath("templates/report.css").read_text(
        encoding="utf-8")
    return _environment().get_template("report.html.j2").render(
        title=f"REI campaign — {data.root.name}",
        css=css,
        planned=len(data.plan.runs), recorded=len(records), passed=passed,
        failed=len(failures), flaky=[m for m in missions if m.flaky],
        repeat=data.plan.repeat, seed=data.plan.seed,
        failures=failures[:MAX_FAILURES], more_failures=max(0, len(failures) - MAX_FAILURES),
        rerun=rerun, mission_of=by_mission, reason_of=verdict_reason,
        page_of=lambda record: run_page_link(data.root, record),
        success_tables=[success_table(missions, "Mission"), group_success_table(records)],
        summary_tables=tables, signal_table=signal_counts(records),
        utility_plot=plots.utility_over_time(data),
        signal_plot=plots.signal_distribution(records),
        descriptor_plot=plots.success_by_descriptor(records),
        maps=maps, more_maps=max(0, len(failures) - MAX_MAPS),
        provenance=data.manifest.get("sessions", []),
    )
