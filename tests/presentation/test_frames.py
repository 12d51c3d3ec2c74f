"""The frames a view shows are the monitor's own judgement of the run: the same signals,
utilities and verdict as the run's events.csv and summary.json, each object's state as the
specification's FAR / CLOSE / COLLISION queries hold it, and a replay paced as asked."""

from __future__ import annotations

import io
import json
from collections.abc import Sequence
from pathlib import Path

import pytest

from rei.runtime.messages import Sample, StreamHeader
from rei.runtime.observation.evaluator.signal_log import SignalRow, read_csv
from rei.runtime.presentation.live import RecordedSource, Watcher, WatchFrame
from rei.runtime.presentation.live.frames import FactorMeter
from rei.runtime.presentation.live.sources import Pacer
from rei.runtime.results import judge

EPS_CLOSE, EPS_COLLISION = 0.25, 0.02
"""The default .vepl's thresholds (ε_close, ε_collision; hysteresis 0)."""


class Collect:
    """A view that keeps what it is shown."""

    def __init__(self) -> None:
        self.header: StreamHeader | None = None
        self.frames: list[WatchFrame] = []
        self.fired: list[SignalRow] = []
        self.samples = 0
        self.closed = False

    def start(self, header: StreamHeader) -> None:
        self.header = header

    def show(self, frame: WatchFrame, sample: Sample | None, fired: Sequence[SignalRow]
             ) -> None:
        self.frames.append(frame)
        self.fired.extend(fired)
        self.samples += sample is not None

    def close(self) -> None:
        self.closed = True


def watch(path: Path, tmp_path: Path, **kwargs: object) -> tuple[Collect, object]:
    view = Collect()
    summary = Watcher([view], None, tmp_path).watch(RecordedSource(path, 0.0), **kwargs)
    return view, summary


@pytest.mark.parametrize("name", ["pass", "fail"])
@pytest.mark.parametrize("stream", ["trace.jsonl", "recording.mcap"])
def test_frames_carry_the_runs_own_signals_utility_and_verdict(
        recorded: dict[str, Path], tmp_path: Path, name: str, stream: str) -> None:
    run = recorded[name]
    view, summary = watch(run / stream, tmp_path)
    assert view.closed
    assert view.fired == read_csv(run / "events.csv")
    live = json.loads((run / "summary.json").read_text())
    last = view.frames[-1]
    assert last.ended is not None and last.ended == summary
    assert last.total_utility == live["total_utility"] == view.fired[-1].total_utility
    assert judge(last.ended) == live["verdict"] == name
    assert [v.status for v in last.ended.verdicts] == [v["status"] for v in live["verdicts"]]
    assert view.samples == live["measurements"]["samples"]
    # every frame's running figures agree with the signals fired up to it
    seen = 0
    for frame in view.frames:
        assert frame.recent == tuple(view.fired[:frame.signals][-len(frame.recent):]) \
            if frame.recent else frame.signals == 0
        assert frame.signals >= seen
        seen = frame.signals


def test_each_objects_state_is_the_geometry_the_thresholds_give(
        recorded: dict[str, Path], tmp_path: Path) -> None:
    view, _ = watch(recorded["fail"] / "trace.jsonl", tmp_path)
    assert view.header is not None
    names = {o.name for o in view.header.objects}
    seen = set()
    for frame in view.frames[:-1]:
        assert {o.name for o in frame.objects} == names
        for o in frame.objects:
            expected = "COLLISION" if o.distance < EPS_COLLISION else \
                "CLOSE" if o.distance < EPS_CLOSE else "FAR"
            # COLLISION of any object wins over CLOSE of the others (thesis Figure 21)
            if expected == "CLOSE" and any(p.distance < EPS_COLLISION for p in frame.objects):
                expected = "FAR"
            assert o.state == expected, (frame.time, o)
            seen.add((o.name, o.state))
    # the run drove into wall_e: it was seen FAR, CLOSE and in COLLISION, as events.csv says
    assert {("wall_e", "FAR"), ("wall_e", "CLOSE"), ("wall_e", "COLLISION")} <= seen


def test_the_robots_state_follows_the_geometric_signals(
        recorded: dict[str, Path], tmp_path: Path) -> None:
    """The screen's 'robot FAR/CLOSE/COLLISION' (thesis Figures 30-31) changes exactly where
    a SIG_GEOM_*_TRANSIT_* signal says it does."""
    for name in ("pass", "fail"):
        view, _ = watch(recorded[name] / "trace.jsonl", tmp_path / name)
        state = "FAR"
        transitions = 0
        for frame in view.frames[:-1]:
            new = [r for r in view.fired[:frame.signals]
                   if r.signal.startswith("SIG_GEOM_") and "_TRANSIT_" in r.signal]
            if new:
                state = new[-1].signal.rsplit("_TRANSIT_", 1)[1]
            transitions = len(new)
            assert frame.robot_state == state, (name, frame.time)
        assert transitions >= 2


def test_a_stop_request_ends_the_watch_as_interrupted(
        recorded: dict[str, Path], tmp_path: Path) -> None:
    calls = []

    def stop() -> bool:
        calls.append(1)
        return len(calls) == 5

    view, summary = watch(recorded["pass"] / "trace.jsonl", tmp_path, stop=stop)
    assert view.samples == 5 and view.closed
    assert summary.outcome == "interrupted" and judge(summary) == "interrupted"  # type: ignore[attr-defined]


class FakeClock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        assert seconds > 0
        self.now += seconds


def test_the_pacer_holds_simulated_time_to_the_asked_speed() -> None:
    clock = FakeClock()
    pacer = Pacer(4.0, clock, clock.sleep)
    for i in range(101):
        pacer.wait(i * 0.1)  # 10 simulated seconds
    assert clock.now == pytest.approx(102.5)
    unpaced = FakeClock()
    fast = Pacer(0.0, unpaced, unpaced.sleep)
    for i in range(101):
        fast.wait(i * 0.1)
    assert unpaced.now == 100.0
    for bad in (-1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="finite number >= 0"):
            Pacer(bad)


def test_the_time_factor_is_simulated_over_wall_seconds() -> None:
    clock = FakeClock()
    meter = FactorMeter(clock, window=2.0)
    assert meter.add(0.0) is None
    for i in range(1, 50):
        clock.now += 0.1
        factor = meter.add(i * 0.5)  # 0.5 simulated s per 0.1 wall s
    assert factor == pytest.approx(5.0)


def test_the_map_draws_the_room_from_above_with_the_robot_where_it_is(
        recorded: dict[str, Path], tmp_path: Path) -> None:
    """simple_wall (thesis 7.2): three floors between walls; the robot drove from the start
    goal to the east wall and stands on the last floor, pressed against wall_e."""
    from rei.runtime.presentation.live.terminal import draw_map

    view, _ = watch(recorded["fail"] / "trace.jsonl", tmp_path)
    first, last = view.frames[0], view.frames[-1]
    lines = [line.rstrip() for line in draw_map(first).plain.splitlines()]
    assert lines == ["  ██████", "██R · G ██", "  ██████"]
    lines = [line.rstrip() for line in draw_map(last).plain.splitlines()]
    assert lines == ["  ██████", "██G · R ██", "  ██████"]
    # a large room is drawn with several tiles to a cell, within the cells given
    nav, _ = watch(recorded["pass"] / "trace.jsonl", tmp_path / "nav")
    small = draw_map(nav.frames[-1], (5, 4)).plain.splitlines()
    assert 0 < len(small) <= 4 and max(len(line) for line in small) <= 10
    assert "R" in "".join(small)


def test_a_specification_without_the_geometric_queries_shows_no_state(
        recorded: dict[str, Path], tmp_path: Path) -> None:
    """examples/navigation/human_safety.vepl judges people only: the objects have no
    FAR / CLOSE / COLLISION state to show (never a made-up FAR), its own signals still come."""
    from rei.runtime.presentation.live.terminal import render
    from tests.conftest import EXAMPLES

    view = Collect()
    vepl = EXAMPLES / "navigation" / "human_safety.vepl"
    summary = Watcher([view], vepl, tmp_path).watch(
        RecordedSource(recorded["pass"] / "trace.jsonl", 0.0))
    last = view.frames[-1]
    assert last.objects and all(o.state is None for o in last.objects)
    assert last.robot_state is None and last.laser_state is None
    assert last.ended == summary and summary.total_utility == last.total_utility
    from rich.console import Console

    console = Console(width=120, record=True, file=io.StringIO())
    console.print(render(last))
    screen = console.export_text()
    assert "robot -" in screen and "walker" in screen
