"""What the page of one run reads from its folder: the summary, the event log, the generated
world and thresholds, and the time series the plots draw, computed from the trace.

Distances are the monitor's own (rei.runtime.observation.model.runtime_model.RuntimeModel over the
trace's
samples), so the plot shows exactly what the automata compared against their thresholds.
Long traces are read whole but kept for plotting at most ``MAX_POINTS`` points per series,
with each bucket's extremes kept: a brief dip into collision or a speed spike must survive
the thinning. This module must never write files.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rei.runtime.artifacts.world import WorldManifest, load_manifest
from rei.runtime.errors import RunError
from rei.runtime.messages import MissionEvent, MissionFacts
from rei.runtime.observation.automata.records import load_generated
from rei.runtime.observation.errors import MonitorError
from rei.runtime.observation.evaluator.signal_log import SignalRow, read_csv
from rei.runtime.observation.model.runtime_model import RuntimeModel
from rei.runtime.observation.recordings import read_stream
from rei.runtime.results import RunSummary

MAX_POINTS = 2000
EXACT_WITHIN = 3.0
"""m: distances below this are computed exactly for every object; beyond it only the nearest
of each group is (the same numbers, a fraction of the time on a room of many walls)."""
EPS_CLOSE = 0.25
EPS_COLLISION = 0.02
"""m: the default specification's thresholds, used when the run folder has no automata."""


@dataclass(frozen=True)
class FailureMark:
    """A failed requirement and the simulation time of the event that decided it."""

    requirement: str
    time: float


@dataclass(frozen=True)
class Thresholds:
    close: float
    collision: float
    source: str
    """Where they were read: the automata file, or 'default' (with why, when the run's
    automata could not be read)."""


@dataclass(frozen=True)
class Series:
    """One quantity over simulation time, thinned for plotting."""

    time: np.ndarray
    value: np.ndarray


@dataclass(frozen=True)
class TraceSeries:
    """What the plots need from the trace."""

    robot: np.ndarray
    """(N, 3) t, x, y of the robot's ground-truth path (thinned)."""
    humans: dict[str, np.ndarray]
    """Each human's (N, 3) t, x, y (thinned like the robot's)."""
    obstacle: Series | None
    """Footprint distance to the nearest wall or object that is not a human; None when the
    world has none."""
    human: Series | None
    """Footprint distance to the nearest human; None when the world has none."""
    speed: Series
    """Ground-truth linear speed, m/s."""
    commanded: Series | None
    """|linear command| the controller returned, m/s; None when the trace does not carry it."""
    speed_limit: float | None
    speed_limit_source: str
    """'speed limit' (the mission's facts) or 'drive limit' (the robot's max_linear)."""
    facts: MissionFacts | None
    """The mission's goals and limits, when the trace's header carries them."""
    events: tuple[MissionEvent, ...]
    samples: int
    end: float


def thin_indices(n: int, max_points: int = MAX_POINTS) -> np.ndarray:
    """Evenly spaced indices (first and last kept) of at most ``max_points`` of ``n``."""
    if n <= max_points:
        return np.arange(n)
    return np.unique(np.linspace(0, n - 1, max_points).round().astype(np.intp))


def thin_extremes(time: np.ndarray, value: np.ndarray, max_points: int = MAX_POINTS) -> Series:
    """At most ``max_points`` points: per bucket of consecutive samples its minimum and its
    maximum, in time order."""
    n = len(value)
    if n <= max_points:
        return Series(time, value)
    buckets = max(1, max_points // 2)
    edges = np.linspace(0, n, buckets + 1).round().astype(np.intp)
    keep: list[int] = []
    finite = np.where(np.isfinite(value), value, np.nan)
    for start, stop in zip(edges[:-1], edges[1:], strict=True):
        chunk = finite[start:stop]
        if stop <= start or np.all(np.isnan(chunk)):
            keep.append(int(start))
            continue
        keep.extend((start + int(np.nanargmin(chunk)), start + int(np.nanargmax(chunk))))
    index = np.unique(np.array(keep, dtype=np.intp))
    return Series(time[index], value[index])


def trace_path(out_dir: Path, trace: Path | None = None) -> Path | None:
    """The trace to draw: the one given, else the folder's trace (or a killed run's partial)."""
    if trace is not None:
        return trace if trace.is_file() else None
    for candidate in (out_dir / "trace.jsonl", out_dir / "trace.jsonl.partial"):
        if candidate.is_file():
            return candidate
    return None


def read_series(path: Path, manifest: WorldManifest | None = None) -> TraceSeries:
    """The time series of a trace; TraceError when it cannot be read."""
    header, samples, read_end = read_stream(path)  # a trace, or a recording (rei replay)
    # Exact footprint distances are worked out only near the robot; the nearest of each
    # group is then refined exactly (FootprintSet.nearest), as the monitor does for humans.
    model = RuntimeModel(header, cutoff=EXACT_WITHIN)
    footprints = model.footprints
    humans_mask = model.human_mask
    obstacles_mask = ~humans_mask
    human_rows = np.flatnonzero(humans_mask)
    times: list[float] = []
    xy: list[tuple[float, float]] = []
    human_xy: list[np.ndarray] = []
    obstacle: list[float] = []
    human: list[float] = []
    speed: list[float] = []
    commanded: list[float] = []
    has_command = False
    events: list[MissionEvent] = []
    try:
        for s in samples:
            distance = model.observe(s).distance
            exact = distance <= EXACT_WITHIN
            times.append(s.time)
            xy.append((s.robot_pose[0], s.robot_pose[1]))
            human_xy.append(s.poses[human_rows, :2].copy())
            obstacle.append(footprints.nearest(distance, exact, obstacles_mask, s.robot_pose,
                                               s.poses) if obstacles_mask.any() else math.inf)
            human.append(footprints.nearest(distance, exact, humans_mask, s.robot_pose,
                                            s.poses) if humans_mask.any() else math.inf)
            speed.append(math.hypot(s.robot_twist[0], s.robot_twist[1]))
            cmd = getattr(s.belief, "cmd", None)
            linear = abs(float(cmd[0])) if cmd is not None else 0.0
            commanded.append(linear)
            # A trace written before the command was recorded reads back (0, 0) throughout:
            # a line at zero would claim the controller never asked to move.
            has_command = has_command or (cmd is not None and (cmd[0] != 0 or cmd[1] != 0))
            events.extend(s.events)
    finally:
        close = getattr(samples, "close", None)
        if close is not None:
            close()
    t = np.array(times, dtype=float)
    keep = thin_indices(len(t))
    robot = np.column_stack((t, np.array(xy, dtype=float).reshape(-1, 2)))[keep]
    humans: dict[str, np.ndarray] = {}
    if len(human_rows) and len(t):
        stacked = np.stack(human_xy)
        for j, row in enumerate(human_rows):
            humans[header.objects[row].name] = np.column_stack((t, stacked[:, j, :]))[keep]
    facts = getattr(header, "mission_facts", None)
    limit = getattr(facts, "speed_limit", None)
    source = "speed limit"
    if limit is None and manifest is not None:
        # a trace without the mission's facts: the drive's own limit still bounds the speed
        limit, source = manifest.drive.max_linear, "drive limit"
    end_line = read_end()
    end = end_line[0] if end_line is not None else (times[-1] if times else 0.0)
    return TraceSeries(
        robot, humans,
        thin_extremes(t, np.array(obstacle)) if obstacles_mask.any() else None,
        thin_extremes(t, np.array(human)) if humans_mask.any() else None,
        thin_extremes(t, np.array(speed)),
        thin_extremes(t, np.array(commanded)) if has_command else None,
        float(limit) if limit is not None and math.isfinite(limit) else None, source,
        facts if isinstance(facts, MissionFacts) else None,
        tuple(events), len(times), float(end))


def read_thresholds(out_dir: Path) -> Thresholds:
    """eps_close and eps_collision of the automata that judged the run."""
    path = out_dir / "automata" / "automata.py"
    default = "default"
    if path.is_file():
        try:
            parameters = getattr(load_generated(path), "PARAMETERS", {})
        except MonitorError as exc:  # e.g. automata of an older REI: say so on the page
            parameters = {}
            default = f"default; automata/automata.py: {str(exc).partition(': ')[2]}"
        except (OSError, SyntaxError):
            parameters = {}
        close, collision = parameters.get("eps_close"), parameters.get("eps_collision")
        if isinstance(close, (int, float)) and isinstance(collision, (int, float)):
            return Thresholds(float(close), float(collision), "automata/automata.py")
    return Thresholds(EPS_CLOSE, EPS_COLLISION, default)


def read_signals(out_dir: Path) -> list[SignalRow]:
    path = out_dir / "events.csv"
    try:
        return read_csv(path)
    except (OSError, ValueError, KeyError):
        return []


def read_manifest(out_dir: Path, trace: Path | None) -> WorldManifest | None:
    """The generated world of the run folder, else the one beside the trace (`rei replay`)."""
    folders = [out_dir / "world"] + ([trace.parent / "world"] if trace is not None else [])
    for folder in folders:
        if (folder / "world.json").is_file():
            try:
                return load_manifest(folder)
            except RunError:
                return None
    return None


def read_summary(out_dir: Path) -> RunSummary:
    path = out_dir / "summary.json"
    try:
        return RunSummary.from_json(json.loads(path.read_text(encoding="utf-8")))
    except (OSError, ValueError, TypeError, KeyError) as exc:
        raise RunError(f"{path}: expected the run's summary.json, could not read it ({exc})"
                       ) from None
