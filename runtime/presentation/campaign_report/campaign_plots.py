"""The campaign's plots: utility over time per mission (thesis Figures 33/36), distribution of
signals (Figure 37), success rate by difficulty descriptor, and top-down maps of failed runs.

Each function returns embeddable text (inline SVG or a PNG data URI) or None when there is
nothing to draw. This module must never write files or choose a global backend.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Literal

import numpy as np

from rei.runtime.campaigns.folder_reader import CampaignData
from rei.runtime.campaigns.run_records import RunRecord
from rei.runtime.campaigns.stats import by_mission, wilson_interval
from rei.runtime.observation.run_folder import SignalEvent, read_events, read_paths
from rei.runtime.presentation.figures import (
    PLOT_WIDTH,
    TEXT_PT,
    TITLE_PT,
    inline_svg,
    label_axes,
    new_figure,
    png_data_uri,
)
from rei.runtime.presentation.maps import draw_paths, map_figure
from rei.runtime.presentation.signals import SIGNAL_ORDER

MAX_LEGEND = 12


REPEAT_STYLES: tuple[Literal["-", "--", ":", "-."], ...] = ("-", "--", ":", "-.")
"""Line styles that tell a mission's repeats apart (with a lighter shade per repeat)."""


def _shade(colour: str, repeat: int) -> tuple[float, float, float]:
    """The mission's colour, mixed with a little more white for each later repeat."""
    from matplotlib.colors import to_rgb  # noqa: PLC0415

    mix = min(0.45, 0.18 * (repeat % len(REPEAT_STYLES)))
    r, g, b = to_rgb(colour)
    return (r + (1 - r) * mix, g + (1 - g) * mix, b + (1 - b) * mix)


def utility_over_time(data: CampaignData) -> str | None:
    """Running total utility against simulation time, one line per run: a colour per
    mission, and a line style and shade per repeat, so two repeats of one room never look
    like one line."""
    from matplotlib.lines import Line2D  # noqa: PLC0415

    lines: list[tuple[str, int, bool, list[SignalEvent]]] = []
    for record in data.records:
        events = read_events(data.run_dir(record))
        if events:
            lines.append((by_mission(record), record.spec.repeat, record.passed, events))
    if not lines:
        return None
    fig = new_figure(PLOT_WIDTH, 4.2)
    ax = fig.add_subplot()
    missions = sorted({m for m, _, _, _ in lines})
    repeats = sorted({r for _, r, _, _ in lines})
    # A colour per mission only while a legend of them fits and no colour repeats; beyond
    # that a line's colour says whether its run passed.
    by_verdict = len(missions) > MAX_LEGEND
    colours = {m: f"C{i % 10}" for i, m in enumerate(missions)}
    labelled: set[str] = set()
    # Hundreds of runs as vector paths make a page of megabytes: raster the lines then.
    raster = len(lines) > 100
    for mission, repeat, passed, events in lines:
        t = [0.0] + [e.time for e in events]
        u = [0.0] + [e.total for e in events]
        key = ("passed" if passed else "did not pass") if by_verdict else mission
        label = key if key not in labelled else None
        labelled.add(key)
        base = ("#2b8a3e" if passed else "#c92a2a") if by_verdict else colours[mission]
        ax.step(t, u, where="post", color=_shade(base, repeat) if not by_verdict else base,
                linestyle=REPEAT_STYLES[repeat % len(REPEAT_STYLES)] if not by_verdict else "-",
                alpha=0.85 if not raster else 0.3, linewidth=1.4, label=label,
                rasterized=raster)
    ax.axhline(0, color="#888", linewidth=0.6)
    label_axes(ax, "simulation time [s]", "total utility", "Utility over time (one line per run)")
    handles, _ = ax.get_legend_handles_labels()
    if not by_verdict and len(repeats) > 1:
        handles += [Line2D([], [], color="#495057",
                           linestyle=REPEAT_STYLES[r % len(REPEAT_STYLES)],
                           label=f"repeat {r + 1}") for r in repeats[:len(REPEAT_STYLES)]]
    ax.legend(handles=handles, fontsize=TEXT_PT, loc="upper left", bbox_to_anchor=(1.0, 1.0),
              frameon=False, title=f"{len(missions)} missions" if by_verdict else None,
              title_fontsize=TEXT_PT)
    return inline_svg(fig)


def signal_distribution(records: Sequence[RunRecord]) -> str | None:
    """Total count of each signal over the campaign (thesis Figure 37)."""
    totals: dict[str, int] = {}
    for record in records:
        if record.summary is not None:
            for signal, count in record.summary.signal_counts.items():
                totals[signal] = totals.get(signal, 0) + count
    if not totals:
        return None
    order = [s for s in SIGNAL_ORDER if s in totals] + sorted(set(totals) - set(SIGNAL_ORDER))
    fig = new_figure(PLOT_WIDTH, 0.9 + 0.32 * len(order))
    ax = fig.add_subplot()
    y = np.arange(len(order))
    ax.barh(y, [totals[s] for s in order], color="#4263eb")
    ax.set_yticks(y, [s.removeprefix("SIG_") for s in order], fontsize=TEXT_PT)
    ax.invert_yaxis()
    for i, s in enumerate(order):
        ax.annotate(str(totals[s]), (totals[s], i), xytext=(3, 0), textcoords="offset points",
                    va="center", fontsize=TEXT_PT)
    label_axes(ax, "occurrences over all runs", title="Distribution of signals")
    return inline_svg(fig)


def descriptors(records: Sequence[RunRecord]) -> list[str]:
    """Numeric parameter/descriptor columns that vary across the campaign."""
    names: dict[str, set[float]] = {}
    for record in records:
        for key, value in record.spec.parameters.items():
            if isinstance(value, (int, float)) and not isinstance(value, bool) and \
                    math.isfinite(value):
                names.setdefault(key, set()).add(float(value))
    # Bookkeeping columns of a suite index are numbers too, but no difficulty.
    skip = {"seed", "index", "design_row", "attempts", "rejected", "repeat"}
    varying = sorted(k for k, v in names.items() if len(v) > 1 and k not in skip)
    # Two names for the same numbers (objects and object_count) are one descriptor.
    seen: dict[tuple[object, ...], str] = {}
    for key in varying:
        column = tuple(r.spec.parameters.get(key) for r in records)
        seen.setdefault(column, key)
    return sorted(seen.values())


def _rate_varies(records: Sequence[RunRecord], name: str) -> bool:
    rates: dict[float, list[bool]] = {}
    for r in records:
        value = r.spec.parameters.get(name)
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            rates.setdefault(float(value), []).append(r.passed)
    return len({sum(v) / len(v) for v in rates.values()}) > 1


def success_by_descriptor(records: Sequence[RunRecord], bins: int = 4) -> str | None:
    """Success rate with Wilson intervals against each numeric difficulty descriptor."""
    # A descriptor along which the success rate does not change carries no information
    names = [n for n in descriptors(records)
             if len({r.passed for r in records if n in r.spec.parameters}) > 1
             and _rate_varies(records, n)]
    if not names:
        return None
    columns = min(3, len(names))
    rows = math.ceil(len(names) / columns)
    fig = new_figure(3.3 * columns, 2.6 * rows)
    for index, name in enumerate(names):
        ax = fig.add_subplot(rows, columns, index + 1)
        pairs = [(float(r.spec.parameters[name]), r.passed) for r in records
                 if isinstance(r.spec.parameters.get(name), (int, float))]
        values = sorted({v for v, _ in pairs})
        if len(values) <= bins:
            edges = None
            groups = [[p for v, p in pairs if v == x] for x in values]
            centres = values
        else:
            edges = np.quantile([v for v, _ in pairs], np.linspace(0, 1, bins + 1))
            edges = np.unique(edges)
            idx = np.clip(np.searchsorted(edges, [v for v, _ in pairs], side="right") - 1,
                          0, len(edges) - 2)
            groups = [[p for (_, p), i in zip(pairs, idx, strict=True) if i == b]
                      for b in range(len(edges) - 1)]
            centres = list((edges[:-1] + edges[1:]) / 2)
        xs, rates, lows, highs = [], [], [], []
        for centre, group in zip(centres, groups, strict=True):
            if not group:
                continue
            low, high = wilson_interval(sum(group), len(group))
            rate = sum(group) / len(group)
            xs.append(centre)
            rates.append(rate)
            lows.append(rate - low)
            highs.append(high - rate)
        ax.errorbar(xs, rates, yerr=[lows, highs], fmt="o-", capsize=3, color="#2b8a3e")
        ax.set_ylim(-0.05, 1.05)
        label_axes(ax, name + (" (quantile bins)" if edges is not None else ""), "success rate")
    fig.suptitle("Success rate by difficulty descriptor (95 % Wilson intervals)", fontsize=TITLE_PT)
    return inline_svg(fig)


def failure_map(data: CampaignData, record: RunRecord) -> str | None:
    """Top-down map of a failed run: room, robot path, humans' paths, where signals fired."""
    try:
        from rei.generators.concrete import load_concrete_mission  # noqa: PLC0415
        from rei.lang.errors import ReiError  # noqa: PLC0415
    except ImportError:
        return None
    try:
        mission = load_concrete_mission(Path(record.spec.mission_file))
    except (ReiError, OSError):
        return None
    run_dir = data.run_dir(record)
    paths = read_paths(run_dir) if run_dir.is_dir() else None
    events = read_events(run_dir) if run_dir.is_dir() else []
    fig, ax = map_figure(mission.world, mission, title=record.spec.run_id, size=4.6)
    if paths is not None:
        draw_paths(ax, paths, events)
    else:
        ax.text(0.5, 0.01, "no trace: path not drawn", transform=ax.transAxes, ha="center",
                fontsize=TEXT_PT, color="#c92a2a")
    return png_data_uri(fig)
