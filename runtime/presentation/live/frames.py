"""What a live view shows: a run's sample stream, monitored, as one ``WatchFrame`` per sample.

``Watcher`` feeds a stream (a ``StreamHeader``, then ``Sample``s, then the end) through the
same generated automata and evaluator as ``rei run`` and ``rei replay`` (``AutomataHost``),
and after each sample hands every ``View`` a frame: each watched object's FAR / CLOSE /
COLLISION state as the specification's own queries judge it (thesis Figures 21, 30-31),
the current task, the signals fired so far with their utilities, the total utility, and the
simulated-time factor (simulated seconds per wall-clock second, measured). The frame is
built from what the monitor already computed: a view never re-judges anything, so what the
screen shows is what events.csv and summary.json say.

Streams come from a ``StreamSource`` (a recorded trace or recording, paced; or a bus). This
module must never import the simulator, a terminal library or a network library: the views
bring their own.
"""

from __future__ import annotations

import math
import time as wallclock
from collections import deque
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, Protocol

import numpy as np

from rei.runtime.errors import RunError
from rei.runtime.messages import Sample, StreamHeader
from rei.runtime.observation.evaluator.signal_log import SignalRow
from rei.runtime.results import RunSummary

GeometricState = Literal["FAR", "CLOSE", "COLLISION"]

COLLISION_QUERY = "findCollisionToObject"
CLOSE_QUERY = "findCloseToObject"
"""The default specification's per-object queries of the geometric states (thesis Table 2;
appendix 9.2.2.1). A specification that keeps these names gets each object's state on the
screen; one without them gets the signals and utilities only."""
LASER_COLLISION_QUERY = "laserSensesCollision"
LASER_CLOSE_QUERY = "laserSensesClose"

RECENT_SIGNALS = 12
"""How many of the latest signals a frame carries (the screen shows what fits)."""
FACTOR_WINDOW = 2.0
"""Wall-clock seconds over which the simulated-time factor is measured: long enough to
smooth the per-sample jitter, short enough to follow a run that slows down."""


class WatchError(RunError):
    """A stream cannot be watched: a specification without what a view needs, a port in use."""


@dataclass(frozen=True)
class ObjectState:
    """One watched body's geometric state relative to the robot at a frame."""

    name: str
    role: str
    state: GeometricState | None
    """None when the specification has no per-object geometric queries."""
    distance: float
    """Footprint distance to the robot, metres (as the monitor measured it)."""
    x: float = 0.0
    y: float = 0.0
    """Where it is (ground truth, world frame, metres): the map draws it there."""


@dataclass(frozen=True)
class TaskLine:
    name: str
    status: str
    """active, succeeded or failed (the monitor's task record)."""
    reason: str = ""


@dataclass(frozen=True)
class WatchFrame:
    """Everything a view shows after one sample (or at the end of the stream)."""

    mission: str
    world: str
    seed: int
    seq: int
    time: float
    """Simulated seconds."""
    robot_pose: tuple[float, float, float]
    nav_state: str
    task: str | None
    """The task being executed, None between tasks."""
    tasks: tuple[TaskLine, ...]
    objects: tuple[ObjectState, ...]
    """Non-wall objects first (declaration order), then the walls nearest first."""
    laser_state: GeometricState | None
    recent: tuple[SignalRow, ...]
    """The latest signals, oldest first."""
    signals: int
    """How many signals fired so far."""
    total_utility: float
    time_factor: float | None
    """Simulated seconds per wall-clock second over the last ``FACTOR_WINDOW``; None until
    measurable."""
    speed: float | None = None
    """The pace asked for (``--speed``) when replaying; None live or unpaced."""
    ended: RunSummary | None = None
    """The run's summary once the stream ended (its verdicts included)."""
    end_time: float | None = None
    """Simulated seconds at the stream's end (its end record's), once it ended."""
    floors: tuple[tuple[float, float], ...] = ()
    """Centres of the floor tiles (the stream header's), for the map."""
    tile: float = 1.0
    goals: tuple[tuple[str, float, float], ...] = ()
    """(name, x, y) of the mission's goals, in order."""

    @property
    def robot_state(self) -> GeometricState | None:
        """The robot's own state (thesis Figure 30's 'FAR'): the worst over all objects."""
        return worst_state([o.state for o in self.objects])


def worst_state(states: Sequence[GeometricState | None]) -> GeometricState | None:
    """COLLISION over CLOSE over FAR; None when no state is known."""
    for worst in ("COLLISION", "CLOSE", "FAR"):
        if worst in states:
            return worst
    return None


class View(Protocol):
    """A consumer of frames: the terminal screen, a Foxglove server, a line log."""

    def start(self, header: StreamHeader) -> None: ...

    def show(self, frame: WatchFrame, sample: Sample | None, fired: Sequence[SignalRow]
             ) -> None:
        """``sample`` is None for the last frame (after the end); ``fired`` are the signals
        fired since the previous frame."""

    def close(self) -> None: ...


End = tuple[float, str, str]
"""(end time, outcome, reason) of a stream, as the trace's end record has it."""


class StreamSource(Protocol):
    """Where a watched stream comes from (a recording, paced; a bus). A source may also
    have ``measurements()``: more of the summary's measurements once the stream ended."""

    speed: float | None
    where: str
    """Names the stream in errors."""

    def open(self) -> tuple[StreamHeader, Iterator[Sample]]: ...

    def end(self) -> End | None:
        """The stream's end (after the samples), None when it stopped without one."""

    def close(self) -> None: ...


class FactorMeter:
    """Simulated seconds per wall-clock second, over the last ``window`` wall seconds."""

    def __init__(self, clock: Callable[[], float], window: float = FACTOR_WINDOW) -> None:
        self.clock = clock
        self.window = window
        self._points: deque[tuple[float, float]] = deque()

    def add(self, sim_time: float) -> float | None:
        now = self.clock()
        points = self._points
        points.append((now, sim_time))
        while len(points) > 2 and now - points[1][0] >= self.window:
            points.popleft()
        wall = now - points[0][0]
        if wall <= 0.0:
            return None
        return (sim_time - points[0][1]) / wall


class Watcher:
    """Monitors one stream for its views (see the module's docstring)."""

    def __init__(self, views: Sequence[View], vepl: Path | None, work_dir: Path,
                 functions: Mapping[str, Callable[..., Any]] | None = None,
                 clock: Callable[[], float] = wallclock.monotonic,
                 parameters: tuple[tuple[str, float], ...] = ()) -> None:
        self.views = list(views)
        self.vepl = vepl
        self.parameters = parameters
        """`--param`: the specification's parameter values in place of the file's."""
        self.work_dir = work_dir
        self.functions = functions
        self.meter = FactorMeter(clock)
        self.frame: WatchFrame | None = None

    def watch(self, source: StreamSource,
              stop: Callable[[], bool] = lambda: False) -> RunSummary:
        """Watch ``source`` to its end (or until ``stop()`` says so after a sample: the
        summary then says 'interrupted'); every view is closed on the way out. The stream is
        judged by ``judge_stream``, `rei replay`'s and `rei monitor`'s own."""
        from rei.runtime.observation.judgement import judge_stream  # noqa: PLC0415

        judging: list[Any] = []  # the monitor's sink, once it judged a sample
        seen = 0
        stopped = False
        last = 0.0

        def judged(sink: Any, sample: Sample) -> None:
            nonlocal seen, last
            if not judging:
                judging.append(sink)
            host = sink.host
            rows = host.log.rows
            fired, seen = rows[seen:], len(rows)
            last = sample.time
            self.frame = self._frame(header, host, sample, source.speed)
            for view in self.views:
                view.show(self.frame, sample, fired)

        def until_stopped(samples: Iterator[Sample]) -> Iterator[Sample]:
            nonlocal stopped
            try:
                for sample in samples:
                    yield sample
                    if stop():
                        stopped = True
                        return
            finally:
                close = getattr(samples, "close", None)
                if close is not None:
                    close()

        def read_end() -> End | None:
            return (last, "interrupted", "stopped watching") if stopped else source.end()

        try:
            header, samples = source.open()
            for view in self.views:
                view.start(header)
            measurements = getattr(source, "measurements", None)
            summary = judge_stream(header, until_stopped(samples), read_end, self.vepl,
                                   self.work_dir, self.functions, None, source.where,
                                   controller="watch", measurements=measurements,
                                   judged=judged, parameters=self.parameters)
            if judging:
                host = judging[0].host
                rows = host.log.rows
                fired = rows[seen:]
                previous = self.frame or self._frame(header, host, None, source.speed)
                end = read_end()
                self.frame = _ended(previous, host, summary,
                                    end[0] if end is not None else last)
            else:
                fired = []
                self.frame = _nothing_seen(header, summary)
            for view in self.views:
                view.show(self.frame, None, fired)
            return summary
        finally:
            source.close()
            for view in self.views:
                view.close()

    def _frame(self, header: StreamHeader, host: Any, sample: Sample | None,
               speed: float | None) -> WatchFrame:
        time = sample.time if sample is not None else 0.0
        factor = self.meter.add(time) if sample is not None else None
        rows = host.log.rows
        return WatchFrame(
            mission=header.mission, world=header.world, seed=header.seed,
            seq=sample.seq if sample is not None else -1, time=time,
            robot_pose=sample.robot_pose if sample is not None else (0.0, 0.0, 0.0),
            nav_state=sample.belief.nav_state.value if sample is not None else "idle",
            task=_current_task(host, sample), tasks=_tasks(host),
            objects=_objects(header, host, sample), laser_state=_laser_state(host),
            recent=tuple(rows[-RECENT_SIGNALS:]), signals=len(rows),
            total_utility=host.log.total, time_factor=factor, speed=speed,
            floors=tuple((x, y) for _, x, y in header.floors), tile=header.tile_size,
            goals=tuple((g.name, g.x, g.y) for g in header.mission_facts.goals)
            if header.mission_facts is not None else ())


def _ended(frame: WatchFrame, host: Any, summary: RunSummary, end_time: float
           ) -> WatchFrame:
    from dataclasses import replace  # noqa: PLC0415

    rows = host.log.rows
    return replace(frame, tasks=_tasks(host), task=None, recent=tuple(rows[-RECENT_SIGNALS:]),
                   signals=len(rows), total_utility=host.log.total, ended=summary,
                   end_time=end_time)


def _nothing_seen(header: StreamHeader, summary: RunSummary) -> WatchFrame:
    """The last frame of a stream that ended before its first sample."""
    return WatchFrame(mission=header.mission, world=header.world, seed=header.seed, seq=-1,
                      time=0.0, robot_pose=(0.0, 0.0, 0.0), nav_state="idle", task=None,
                      tasks=(), objects=(), laser_state=None, recent=(), signals=0,
                      total_utility=summary.total_utility, time_factor=None, ended=summary,
                      end_time=0.0, floors=tuple((x, y) for _, x, y in header.floors),
                      tile=header.tile_size)


def _current_task(host: Any, sample: Sample | None) -> str | None:
    if sample is not None and sample.belief.task is not None:
        return sample.belief.task
    active = [t.name for t in host.model.tasks if t.status == "active"]
    return active[-1] if active else None


def _tasks(host: Any) -> tuple[TaskLine, ...]:
    return tuple(TaskLine(t.name, t.status, t.reason) for t in host.model.tasks)


def _objects(header: StreamHeader, host: Any, sample: Sample | None
             ) -> tuple[ObjectState, ...]:
    q = host.prev_q
    distance = np.asarray(host.prev_inputs.distance, dtype=float)
    collision = q.get(COLLISION_QUERY)
    close = q.get(CLOSE_QUERY)
    judged = (collision is not None and close is not None
              and np.shape(collision) == np.shape(close) == (len(header.objects),))
    out = []
    for i, o in enumerate(header.objects):
        state: GeometricState | None = None
        if judged:
            state = "COLLISION" if collision[i] else "CLOSE" if close[i] else "FAR"
        d = float(distance[i]) if i < len(distance) else math.inf
        x, y = (float(sample.poses[i][0]), float(sample.poses[i][1])) \
            if sample is not None and i < len(sample.poses) else (0.0, 0.0)
        out.append(ObjectState(o.name, o.role, state, d, x, y))
    others = [o for o in out if o.role != "wall"]
    walls = sorted((o for o in out if o.role == "wall"), key=lambda o: o.distance)
    return tuple(others + walls)


def _laser_state(host: Any) -> GeometricState | None:
    q = host.prev_q
    collision, close = q.get(LASER_COLLISION_QUERY), q.get(LASER_CLOSE_QUERY)
    if collision is None or close is None:
        return None
    return "COLLISION" if bool(np.any(collision)) else "CLOSE" if bool(np.any(close)) else "FAR"
