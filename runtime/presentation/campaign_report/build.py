"""Building everything a campaign folder reports: results tables, junit.xml, clusters.json (the
failure clusters, rei.runtime.campaigns.failure_clusters) and report.html.

``build_report`` reads the store only; it can run while no campaign runs (`rei report DIR`),
and gives the same bytes for the same records. This module must never run a mission.
"""

from __future__ import annotations

import json
import shlex
from dataclasses import dataclass
from pathlib import Path

from rei.generators.output import write_atomic
from rei.runtime.campaigns.coverage import (
    COVERAGE_JSON,
    Coverage,
    behaviour_coverage,
    coverage_json,
    situation_coverage,
)
from rei.runtime.campaigns.failure_clusters import CLUSTERS_JSON, clusters, clusters_json, failures
from rei.runtime.campaigns.folder_reader import load_campaign
from rei.runtime.campaigns.plan import RunSpec
from rei.runtime.campaigns.results_table import write_tables
from rei.runtime.campaigns.run_records import RunRecord
from rei.runtime.presentation.junit import junit_xml


@dataclass(frozen=True)
class ReportOutcome:
    root: Path
    planned: int
    records: tuple[RunRecord, ...]
    html: Path | None
    junit: Path
    behaviours: Coverage
    situations: Coverage

    @property
    def failed(self) -> tuple[RunRecord, ...]:
        return tuple(r for r in self.records if not r.passed)

    @property
    def all_passed(self) -> bool:
        return not self.failed and len(self.records) == self.planned

    def describe(self) -> str:
        lines = [f"{len(self.records)} of {self.planned} runs recorded, "
                 f"{len(self.records) - len(self.failed)} passed, {len(self.failed)} failed"]
        lines.append(self.behaviours.line())
        lines.append(self.situations.line() + f" (coverage: {self.root / COVERAGE_JSON})")
        lines.append(f"results: {self.root / 'results.parquet'} (and results.csv)")
        lines.append(f"junit:   {self.junit}")
        if self.html is not None:
            lines.append(f"report:  {self.html}")
        return "\n".join(lines)


def rerun_command(spec: RunSpec) -> str:
    """The one command that repeats a run exactly (same mission, seed and options)."""
    return shlex.join(["rei", *spec.run_argv(f"rerun/{spec.run_id}")])


def build_report(root: Path, *, html: bool = True) -> ReportOutcome:
    data = load_campaign(root)
    write_tables(root, list(data.records))
    rerun = {r.spec.run_id: rerun_command(r.spec) for r in data.records}
    junit = root / "junit.xml"
    write_atomic(junit, junit_xml(data.records, rerun))
    found = clusters(failures([r for r in data.records if not r.passed], data.run_dir), rerun,
                     root)
    write_atomic(root / CLUSTERS_JSON,
                 (json.dumps(clusters_json(found), indent=2, sort_keys=True) + "\n").encode())
    behaviours, situations = behaviour_coverage(data.records), situation_coverage(data.records)
    write_atomic(root / COVERAGE_JSON, coverage_json(behaviours, situations))
    page = None
    if html:
        from rei.runtime.presentation.campaign_report.html import (  # noqa: PLC0415  (matplotlib is slow)
            render_html,
        )

        page = root / "report.html"
        write_atomic(page, render_html(data, rerun, behaviours, situations, found)
                     .encode("utf-8"))
    return ReportOutcome(root, len(data.plan.runs), data.records, page, junit, behaviours,
                         situations)
