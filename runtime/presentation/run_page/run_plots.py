"""The plots of one run's page, after the thesis's monitor view (Figures 30–31): the mission's
events and the signals over time with the running total utility, the distances the monitor
compared against its thresholds, the speed against the limit, and the map with the path
coloured by time. Every plot marks when requirements failed, so a reader can line up cause
and verdict.

Each function returns embeddable text (inline SVG, or a PNG data URI for the map) or None
when there is nothing to draw. This module must never write files or choose a global backend.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.lines import Line2D

from rei.runtime.messages import MissionEvent
from rei.runtime.observation.evaluator.signal_log import SignalRow
from rei.runtime.observation.run_folder import Paths
from rei.runtime.presentation.figures import (
    PLOT_WIDTH,
    TEXT_PT,
    inline_svg,
    label_axes,
    new_figure,
    png_data_uri,
)
from rei.runtime.presentation.maps import draw_human_paths, map_figure
from rei.runtime.presentation.run_page.run_data import FailureMark, Series, Thresholds, TraceSeries
from rei.runtime.presentation.signals import SIGNAL_ORDER

if TYPE_CHECKING:
    from matplotlib.artist import Artist
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from rei.generators.concrete import ConcreteMission, ConcreteWorld

WIDTH = PLOT_WIDTH
"""inches at 96 dpi (figures.PLOT_WIDTH)."""
FAIL = "#c92a2a"
PASS = "#237032"
CLOSE = "#e67700"
NEUTRAL = "#868e96"
DISTANCE_AXIS_MIN = 1.5
"""m: the distance axis shows at least this much, at most six CLOSE thresholds beyond it."""
MAX_TASK_LANES = 30
"""Tasks drawn one lane each; a mission of many cycles shows its first ones."""


SVG_ID = re.compile(r'id="([a-z][0-9a-f]{10})"')


def _svg(fig: Figure, name: str) -> str:
    """The figure as inline SVG with its clip, marker and hatch ids renamed ``NAME-1``...

    matplotlib names them by hashing float coordinates, whose last bits differ between a
    process that ran the simulator and one that did not (floating-point flags set by the
    physics library): renaming in order of appearance keeps the page's bytes equal, and
    the name keeps the ids of several figures on one page apart."""
    text = inline_svg(fig)
    for n, old in enumerate(dict.fromkeys(SVG_ID.findall(text)), start=1):
        # the hash appears only as the id and in references to it (url(#..), href="#..")
        text = text.replace(old, f"{name}-{n}")
    return text


def _mark_failures(ax: Axes, failures: Sequence[FailureMark], label: bool, end: float
                   ) -> None:
    for i, f in enumerate(failures):
        ax.axvline(f.time, color=FAIL, linestyle=":", linewidth=1.2, zorder=1,
                   label="requirement failed" if i == 0 else None)
        if label:
            # staggered, so failures decided at the same instant stay legible; near the
            # end of the run the label goes left of the line, inside the axes
            right = f.time > 0.75 * end
            ax.annotate(f.requirement, (f.time, 1.0), xycoords=("data", "axes fraction"),
                        xytext=(-3 if right else 3, -4 - 11 * (i % 4)),
                        textcoords="offset points", fontsize=TEXT_PT, color=FAIL,
                        ha="right" if right else "left", va="top",
                        bbox={"boxstyle": "square,pad=0.1", "fc": "white", "ec": "none",
                              "alpha": 0.8})


def _tasks(events: Sequence[MissionEvent]) -> list[tuple[str, float, float | None, str, str]]:
    """(label, start, end or None, 'success' | 'fail' | 'open', reason) per started task."""
    tasks: list[tuple[str, float, float | None, str, str]] = []
    open_: dict[str, int] = {}
    for e in events:
        key = str(e.index) if e.index is not None else (e.task or "")
        if e.kind == "task_start":
            open_[key] = len(tasks)
            label = f"#{e.index} {e.task}" if e.index is not None else str(e.task)
            tasks.append((label, e.time, None, "open", ""))
        elif e.kind in ("task_success", "task_fail") and key in open_:
            i = open_.pop(key)
            label, start, _, _, _ = tasks[i]
            tasks[i] = (label, start, e.time, "success" if e.kind == "task_success" else "fail",
                        e.reason)
    return tasks


def timeline(events: Sequence[MissionEvent], signals: Sequence[SignalRow], end: float,
             failures: Sequence[FailureMark]) -> str | None:
    """Three lanes over simulation time: the tasks (bars coloured by how they ended, with the
    executor's reason), every signal (x: negative utility, o: positive), the total utility."""
    if not events and not signals:
        return None
    tasks = _tasks(events)[:MAX_TASK_LANES]
    names = sorted({r.signal for r in signals},
                   key=lambda s: (SIGNAL_ORDER.index(s) if s in SIGNAL_ORDER else 99, s))
    task_rows = max(1, len(tasks))
    heights = [0.4 + 0.3 * task_rows, 0.4 + 0.22 * max(1, len(names)), 2.4]
    fig = new_figure(WIDTH, sum(heights) + 1.0)
    grid = fig.add_gridspec(3, 1, height_ratios=heights)
    ax_tasks = fig.add_subplot(grid[0])
    ax_signals = fig.add_subplot(grid[1], sharex=ax_tasks)
    ax_utility = fig.add_subplot(grid[2], sharex=ax_tasks)
    colours = {"success": PASS, "fail": FAIL, "open": NEUTRAL}
    for row, (_, start, stop, status, reason) in enumerate(tasks):
        finish = stop if stop is not None else end
        ax_tasks.barh(row, max(finish - start, end * 0.004), left=start, height=0.6,
                      color=colours[status], alpha=0.8)
        text = {"success": "succeeded", "fail": "failed", "open": "not ended"}[status]
        if reason:
            # the whole reason is in the events table below the plot
            text += f": {reason if len(reason) <= 28 else reason[:25] + '…'}"
        # near the end of the run the words go left of the bar's end, inside the axes
        inside = finish > 0.6 * end
        ax_tasks.annotate(text, (finish, row), xytext=(-4 if inside else 4, 0),
                          textcoords="offset points", va="center",
                          ha="right" if inside else "left", fontsize=TEXT_PT, color=colours[status],
                          bbox={"boxstyle": "square,pad=0.1", "fc": "white", "ec": "none",
                                "alpha": 0.85}).set_in_layout(False)
    for e in events:
        if e.kind in ("begin", "end"):
            ax_tasks.axvline(e.time, color="#212529", linewidth=0.8, linestyle="--")
            ax_tasks.annotate(f"mission {e.kind}", (e.time, 1.0),
                              xycoords=("data", "axes fraction"), xytext=(2, 2),
                              textcoords="offset points", fontsize=TEXT_PT)
    ax_tasks.set_yticks(range(len(tasks)), [t[0] for t in tasks], fontsize=TEXT_PT)
    ax_tasks.set_ylim(task_rows - 0.4, -0.6)
    label_axes(ax_tasks, y="tasks",
               title="Mission events, signals and total utility over time", title_pad=14)
    _mark_failures(ax_tasks, failures, False, end)
    lane = {name: i for i, name in enumerate(names)}
    for positive in (False, True):
        rows = [r for r in signals if (r.utility >= 0) == positive]
        if rows:
            ax_signals.scatter([r.time for r in rows], [lane[r.signal] for r in rows],
                               marker="o" if positive else "x", s=26, zorder=3,
                               color=PASS if positive else FAIL,
                               facecolors="none" if positive else None,
                               label="positive utility" if positive else "negative utility")
    ax_signals.set_yticks(range(len(names)), [n.removeprefix("SIG_") for n in names],
                          fontsize=TEXT_PT)
    ax_signals.set_ylim(max(len(names), 1) - 0.5, -0.5)  # no signal: one empty lane
    label_axes(ax_signals, y="signals")
    ax_signals.grid(axis="y", color="#e9ecef", linewidth=0.6)
    _mark_failures(ax_signals, failures, False, end)
    t = [0.0] + [r.time for r in signals] + [end]
    u = [0.0] + [r.total_utility for r in signals]
    u.append(u[-1])
    ax_utility.step(t, u, where="post", color="#4263eb", linewidth=1.4, label="total utility")
    ax_utility.axhline(0, color="#adb5bd", linewidth=0.6)
    label_axes(ax_utility, "simulation time [s]", "total utility")
    _mark_failures(ax_utility, failures, True, end)
    handles = [h for ax in (ax_signals, ax_utility) for h in ax.get_legend_handles_labels()[0]]
    _legend_below(fig, _unique(handles))
    for ax in (ax_tasks, ax_signals, ax_utility):
        ax.set_xlim(0, max(end, 1e-9) * 1.01)
    for ax in (ax_tasks, ax_signals):
        ax.tick_params(labelbottom=False)
    return _svg(fig, "timeline")


def _unique(handles: list[Artist]) -> list[Artist]:
    """One legend entry per label (every lane marks the same failures)."""
    seen: dict[str, Artist] = {}
    for handle in handles:
        seen.setdefault(str(handle.get_label()), handle)
    return list(seen.values())


def _legend_below(fig: Figure, handles: list[Artist]) -> None:
    """The legend under the plot, across its width: beside it, it took a third of an
    800 px page's plot width."""
    if handles:
        fig.legend(handles=handles, loc="outside lower center", ncols=min(3, len(handles)),
                   fontsize=TEXT_PT, frameon=False)


def _line(ax: Axes, series: Series, **style: object) -> None:
    ax.plot(series.time, series.value, **style)  # type: ignore[arg-type]


def distance_axis(values: Sequence[np.ndarray], close: float) -> tuple[float, float, bool]:
    """(bottom, top, cut) of the distance axis for the finite values of each line: the top
    is at most a few CLOSE thresholds (at least DISTANCE_AXIS_MIN) or just above each line's
    closest approach; ``cut`` when some value lies above the top (drawn on the top edge)."""
    finite = np.concatenate(values) if len(values) else np.zeros(0)
    low = min(0.0, float(finite.min())) if len(finite) else 0.0
    high = float(finite.max()) if len(finite) else close
    closest = max((float(v.min()) for v in values), default=0.0)
    cut = max(DISTANCE_AXIS_MIN, 6 * close, 1.3 * closest)
    is_cut = high > cut
    top = cut if is_cut else (high * 1.08 if high > 0 else close * 2)
    return low, max(top, close * 1.3), is_cut


def distances(series: TraceSeries, thresholds: Thresholds, failures: Sequence[FailureMark]
              ) -> str | None:
    """Footprint distance to the nearest obstacle and human, against CLOSE and COLLISION."""
    if series.obstacle is None and series.human is None:
        return None
    fig = new_figure(WIDTH, 3.8)
    ax = fig.add_subplot()
    # Centimetres matter near the thresholds; metres of clearance across a room would
    # flatten them to one line, so the axis stops at a few times the CLOSE threshold, or
    # just above the closest approach of each line, so that every line shows its dips.
    # Above the cut a line runs along the top edge (never off the chart), and the label
    # names the value the axis really ends at.
    values = [v for v in (s.value[np.isfinite(s.value)] for s in (series.obstacle, series.human)
                          if s is not None) if len(v)]
    low, top, is_cut = distance_axis(values, thresholds.close)
    for line, colour, label in ((series.obstacle, "#1c7ed6", "nearest obstacle (walls, objects)"),
                                (series.human, "#e8590c", "nearest human")):
        if line is not None:
            shown = Series(line.time, np.minimum(line.value, top)) if is_cut else line
            _line(ax, shown, color=colour, linewidth=1.3, label=label)
    ax.axhline(thresholds.close, color=CLOSE, linestyle="--", linewidth=1.1,
               label=f"CLOSE threshold ({thresholds.close:g} m)")
    ax.axhline(thresholds.collision, color=FAIL, linestyle="--", linewidth=1.1,
               label=f"COLLISION threshold ({thresholds.collision:g} m)")
    _mark_failures(ax, failures, True, series.end)
    ax.set_ylim(low - 0.02 * (top - low), top)
    ax.set_xlim(0, max(series.end, 1e-9) * 1.01)
    label_axes(ax, "simulation time [s]",
               "footprint distance [m]" + (f"\n(axis ends at {top:.3g} m: farther\nis drawn "
                                           f"on the top edge)" if is_cut else ""),
               "Distance to the nearest obstacle and human (the monitor's geometry)")
    ax.grid(color="#f1f3f5", linewidth=0.6)
    _legend_below(fig, ax.get_legend_handles_labels()[0])
    return _svg(fig, "distance")


def speed(series: TraceSeries, failures: Sequence[FailureMark]) -> str | None:
    """Driven (ground truth) and commanded speed against the speed limit."""
    if not len(series.speed.time):
        return None
    fig = new_figure(WIDTH, 3.2)
    ax = fig.add_subplot()
    _line(ax, series.speed, color="#1c7ed6", linewidth=1.3, label="driven (ground truth)")
    if series.commanded is not None:
        _line(ax, series.commanded, color="#7048e8", linewidth=1.1, linestyle="--",
              label="commanded |linear|")
    if series.speed_limit is not None:
        ax.axhline(series.speed_limit, color=FAIL, linestyle="--", linewidth=1.1,
                   label=f"{series.speed_limit_source} ({series.speed_limit:g} m/s)")
    _mark_failures(ax, failures, True, series.end)
    ax.set_xlim(0, max(series.end, 1e-9) * 1.01)
    fastest = max([float(np.nanmax(series.speed.value))] + (
        [float(np.nanmax(series.commanded.value))] if series.commanded is not None else []) + (
        [series.speed_limit] if series.speed_limit is not None else []))
    # headroom above the limit: a robot driving at the limit must not hide the limit's line
    ax.set_ylim(0, max(fastest, 1e-3) * 1.15)
    label_axes(ax, "simulation time [s]", "speed [m/s]", "Speed over time")
    ax.grid(color="#f1f3f5", linewidth=0.6)
    _legend_below(fig, ax.get_legend_handles_labels()[0])
    return _svg(fig, "speed")


def run_map(world: ConcreteWorld, mission: ConcreteMission | None, series: TraceSeries,
            failures: Sequence[FailureMark], title: str) -> str:
    """The room from above: the robot's path coloured by time, the humans' paths, where and
    when each requirement failed."""
    fig, ax = map_figure(world, mission, title=title, compact=False, size=5.0,
                         margin=(4.2, 1.6))
    world_legend = ax.get_legend()
    draw_human_paths(ax, Paths(series.robot, series.humans))
    robot = series.robot
    handles: list[Line2D] = []
    if len(robot) >= 2:
        xy = robot[:, 1:3]
        segments = list(np.stack((xy[:-1], xy[1:]), axis=1))  # one (2, 2) line per step
        path = LineCollection(segments, cmap="viridis", linewidth=2.2, zorder=8)
        path.set_array(robot[:-1, 0])
        path.set_clim(float(robot[0, 0]), float(max(robot[-1, 0], robot[0, 0] + 1e-9)))
        ax.add_collection(path)
        bar = fig.colorbar(path, ax=ax, location="bottom", shrink=0.6, pad=0.02, aspect=40)
        bar.set_label("simulation time [s]", fontsize=TEXT_PT)
        bar.ax.tick_params(labelsize=TEXT_PT)
        ax.plot(robot[-1, 1], robot[-1, 2], marker="s", color="#212529", markersize=6,
                zorder=9)
        handles.append(Line2D([], [], color="#21918c", linewidth=2.2,
                              label="robot path (colour: time)"))
        handles.append(Line2D([], [], color="#212529", marker="s", linestyle="none",
                              label="robot at the end"))
    if series.humans:
        handles.append(Line2D([], [], color="#e8590c", linestyle="--", label="human path"))
    if len(robot) and failures:
        times = [f.time for f in failures]
        xs = np.interp(times, robot[:, 0], robot[:, 1])
        ys = np.interp(times, robot[:, 0], robot[:, 2])
        ax.scatter(xs, ys, marker="X", s=110, color=FAIL, edgecolors="white", linewidths=0.8,
                   zorder=11)
        for i, (f, x, y) in enumerate(zip(failures, xs, ys, strict=True)):
            ax.annotate(f"{f.requirement}\nt = {f.time:g} s", (x, y),
                        xytext=(10, 14 + 24 * i), textcoords="offset points", fontsize=TEXT_PT,
                        color=FAIL, zorder=12,
                        bbox={"boxstyle": "round,pad=0.2", "fc": "white", "ec": FAIL,
                              "alpha": 0.9},
                        arrowprops={"arrowstyle": "-", "color": FAIL, "lw": 0.8})
        handles.append(Line2D([], [], color=FAIL, marker="X", linestyle="none",
                              markersize=9, label="requirement failed here"))
    if handles:
        if world_legend is not None:
            ax.add_artist(world_legend)
        ax.legend(handles=handles, loc="lower left", bbox_to_anchor=(1.01, 0.0), fontsize=TEXT_PT,
                  frameon=False)
    return png_data_uri(fig, dpi=96)
