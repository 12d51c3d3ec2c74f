"""The page of one run (report.html beside events.csv): what a test engineer reads first.

``write_run_page(DIR)`` reads what `rei run` (or `rei replay`) wrote into DIR — summary.json,
events.csv, the trace, world/world.json and the automata's thresholds — and writes one
self-contained HTML page: the run's verdict, the requirement verdicts, the mission's events
and signals over time, distances against the CLOSE and COLLISION thresholds, the speed
against the limit, and the map with the path coloured by time. Same folder, same bytes.
A campaign report links to these pages (rei.runtime.presentation.campaign_report.html).
This module must never run a mission or change any file but report.html.
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import jinja2

from rei.generators.output import write_atomic
from rei.runtime.artifacts.world import WorldManifest
from rei.runtime.messages import MissionEvent
from rei.runtime.observation.evaluator.signal_log import SignalRow
from rei.runtime.presentation.run_page.run_data import (
    FailureMark,
    Thresholds,
    TraceSeries,
    read_manifest,
    read_series,
    read_signals,
    read_summary,
    read_thresholds,
    trace_path,
)
from rei.runtime.presentation.templating import environment
from rei.runtime.results import PAGE_POLICIES, RunSummary, judge
from rei.runtime.trace import TraceError

PAGE = "report.html"
BRIEF_MARK = '<meta name="rei-page" content="brief">'
"""In the head of a brief page (verdicts, no plots or map): `rei page` draws the full one."""
BRIEF_NOTE = ("Not drawn: this run passed, and it was run with --page failed (a campaign's "
              "default), which draws the plots and the map only for runs that did not pass. "
              "Draw them with `rei page` on this run's folder or on its campaign's folder.")
STATUS_WORDS = {"pass": "pass", "fail": "fail", "inconclusive": "inconclusive",
                "not_applicable": "not applicable"}
EVENT_WORDS = {"begin": "mission began", "task_start": "task started",
               "task_success": "task succeeded", "task_fail": "task failed",
               "end": "mission ended"}


@dataclass(frozen=True)
class Plot:
    """An embeddable figure with the words a reader without images gets instead."""

    id: str
    title: str
    content: str
    alt: str


def _environment() -> jinja2.Environment:
    env = environment()
    env.filters["seconds"] = lambda v: "end of run" if v is None else f"{v:g} s"
    return env


def _failures(summary: RunSummary, end: float) -> list[FailureMark]:
    # a failure decided at the end of the run (no deciding event) is drawn at the end
    return [FailureMark(v.requirement, v.decided_at if v.decided_at is not None else end)
            for v in summary.verdicts if v.status == "fail"]


def _event_rows(events: tuple[MissionEvent, ...]) -> list[tuple[float, str, str, str]]:
    rows = []
    for e in events:
        task = f"#{e.index} {e.task}" if e.index is not None and e.task else (e.task or "")
        rows.append((e.time, EVENT_WORDS.get(e.kind, e.kind), task, e.reason))
    return rows


def _css() -> str:
    folder = resources.files("rei.runtime.presentation").joinpath("templates")
    return "\n".join(folder.joinpath(name).read_text(encoding="utf-8")
                     for name in ("report.css", "run.css"))


@dataclass(frozen=True)
class FaultRow:
    name: str
    entry: str
    intervals: tuple[tuple[float, float | None], ...]
    counts: tuple[tuple[str, int], ...]


def _fault_rows(summary: RunSummary) -> list[FaultRow]:
    """The faults the run injected, from its summary (written by the run itself, so trusted
    in shape; anything else is left out rather than shown wrong)."""
    m = summary.measurements
    injected, timeline = m.get("faults_injected"), m.get("faults")
    statistics = m.get("fault_statistics") or {}
    if not isinstance(injected, list) or not isinstance(timeline, list):
        return []
    rows = []
    for item in injected:
        if not isinstance(item, dict):
            continue
        name = str(item.get("fault", ""))
        counts = statistics.get(name) if isinstance(statistics, dict) else None
        try:
            intervals = tuple((float(t["start"]),
                               None if t.get("end") is None else float(t["end"]))
                              for t in timeline if isinstance(t, dict) and t.get("fault") == name)
            shown = tuple((str(k), int(v)) for k, v in counts.items()) \
                if isinstance(counts, dict) else ()
        except (KeyError, TypeError, ValueError):
            continue
        rows.append(FaultRow(name, str(item.get("entry", "")), intervals, shown))
    return rows


def render_run_page(summary: RunSummary, signals: list[SignalRow], series: TraceSeries | None,
                    thresholds: Thresholds, map_image: str | None, map_note: str,
                    trace_note: str, trace_name: str = "") -> str:
    """The page's HTML from what was read (no file access here but the templates)."""
    from rei.runtime.presentation.run_page import (  # noqa: PLC0415  (matplotlib: full pages only)
        run_plots,
    )

    end = series.end if series is not None else summary.duration
    failures = _failures(summary, end)
    plots: list[Plot] = []
    timeline = run_plots.timeline(series.events if series is not None else (), signals, end,
                                  failures)
    if timeline is not None:
        plots.append(Plot("timeline-plot", "Timeline", timeline,
                          "timeline of the mission's tasks, the signals and the total utility "
                          "over simulation time"))
    if series is not None:
        distance = run_plots.distances(series, thresholds, failures)
        if distance is not None:
            plots.append(Plot("distance-plot", "Distances", distance,
                              f"distance to the nearest obstacle and human over time, with "
                              f"the CLOSE ({thresholds.close:g} m) and COLLISION "
                              f"({thresholds.collision:g} m) thresholds"))
        speed = run_plots.speed(series, failures)
        if speed is not None:
            plots.append(Plot("speed-plot", "Speed", speed,
                              "driven and commanded speed over time against the speed limit"))
    return _render(summary, signals, series, thresholds, map_image, map_note, trace_note,
                   trace_name, plots, failures)


def render_brief_page(summary: RunSummary, thresholds: Thresholds, trace_name: str = "") -> str:
    """The brief page of a run that passed: the header, the requirements and the faults, no
    plots and no map (so no trace read and no matplotlib), with ``BRIEF_NOTE``."""
    return _render(summary, [], None, thresholds, None, BRIEF_NOTE, "", trace_name, [],
                   _failures(summary, summary.duration), brief=True)


def _render(summary: RunSummary, signals: list[SignalRow], series: TraceSeries | None,
            thresholds: Thresholds, map_image: str | None, map_note: str, trace_note: str,
            trace_name: str, plots: list[Plot], failures: list[FailureMark],
            brief: bool = False) -> str:
    return _environment().get_template("run.html.j2").render(
        title=f"REI run — {summary.mission}", css=_css(), summary=summary, brief=brief,
        brief_mark=BRIEF_MARK, verdict=judge(summary), verdicts=summary.verdicts,
        status_words=STATUS_WORDS,
        events=_event_rows(series.events) if series is not None else [],
        signals=signals, plots=plots, map_image=map_image, map_note=map_note,
        trace_note=trace_note, thresholds=thresholds, failures=failures,
        samples=series.samples if series is not None else 0,
        speed_limit=series.speed_limit if series is not None else None,
        speed_limit_source=series.speed_limit_source if series is not None else "",
        trace_name=trace_name, faults=_fault_rows(summary),
        has_command=series is not None and series.commanded is not None)


def _map(manifest: WorldManifest | None, series: TraceSeries | None, summary: RunSummary,
         failures: list[FailureMark]) -> tuple[str | None, str]:
    if manifest is None:
        return None, "No map: the run folder has no generated world (world/world.json)."
    if series is None:
        return None, "No map: the run has no readable trace."
    from rei.runtime.presentation.maps import (  # noqa: PLC0415
        mission_from_facts,
        world_from_manifest,
    )
    from rei.runtime.presentation.run_page import run_plots  # noqa: PLC0415

    world = world_from_manifest(manifest)
    mission = mission_from_facts(summary.mission, world, series.facts) \
        if series.facts is not None else None
    title = f"{summary.mission} in {summary.room}"
    return run_plots.run_map(world, mission, series, failures, title), ""


def write_run_page(out_dir: Path, trace: Path | None = None, *, policy: str = "all"
                   ) -> Path | None:
    """Write DIR/report.html from the run's outputs (the trace given, else DIR's own) as
    ``policy`` (``PAGE_POLICIES``) asks: the full page, the brief one for a run that passed
    under ``failed``, none under ``none`` (None returned). RunError when DIR has no readable
    summary.json."""
    if policy not in PAGE_POLICIES:
        raise ValueError(f"page policy: expected one of {', '.join(PAGE_POLICIES)}, "
                         f"found {policy!r}")
    if policy == "none":
        return None
    out_dir = Path(out_dir)
    summary = read_summary(out_dir)
    path = trace_path(out_dir, trace)
    # linked only when it sits in the folder (a replayed trace may live anywhere)
    trace_name = path.name if path is not None and path.parent.resolve() == out_dir.resolve() \
        else ""
    target = out_dir / PAGE
    if policy == "failed" and judge(summary) == "pass":
        write_atomic(target, render_brief_page(summary, read_thresholds(out_dir),
                                               trace_name).encode("utf-8"))
        return target
    signals = read_signals(out_dir)
    manifest = read_manifest(out_dir, path)
    series: TraceSeries | None = None
    trace_note = ""
    if path is None:
        trace_note = "No trace: the plots over time and the map are not drawn."
    else:
        try:
            series = read_series(path, manifest)
        except TraceError as exc:
            trace_note = f"The trace could not be read ({exc}); plots are not drawn."
    end = series.end if series is not None else summary.duration
    map_image, map_note = _map(manifest, series, summary, _failures(summary, end))
    page = render_run_page(summary, signals, series, read_thresholds(out_dir), map_image,
                           map_note, trace_note, trace_name)
    write_atomic(target, page.encode("utf-8"))
    return target


def page_is_full(out_dir: Path) -> bool:
    """Whether DIR/report.html exists and is a full page (not a brief one)."""
    try:
        with (Path(out_dir) / PAGE).open("rb") as page:
            head = page.read(4096)
    except OSError:
        return False
    return BRIEF_MARK.encode() not in head


__all__ = ["BRIEF_MARK", "PAGE", "PAGE_POLICIES", "page_is_full", "render_brief_page",
           "render_run_page", "write_run_page"]
