"""Running a stream through the monitor in tests, and reading its event log."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from rei.runtime.messages import Sample, StreamHeader
from rei.runtime.observation.evaluator.signal_log import SignalRow, read_csv
from rei.runtime.observation.evaluator.summary import MonitorResult
from rei.runtime.observation.monitor import MonitorSink, generate_automata


def monitor(header: StreamHeader, samples: Sequence[Sample], out: Path,
            vepl: Path | None = None, automata: Path | None = None, outcome: str = "completed",
            ) -> tuple[list[SignalRow], MonitorResult]:
    sink = MonitorSink(vepl, out, automata=automata)
    sink.start(header)
    for s in samples:
        sink.feed(s)
    sink.finish(samples[-1].time if samples else 0.0, outcome, "")
    assert sink.result is not None
    return read_csv(out / "events.csv"), sink.result


def default_automata(tmp: Path) -> Path:
    return generate_automata(None, tmp / "automata")


def geom(rows: Sequence[SignalRow]) -> list[tuple[float, str]]:
    return [(r.time, r.signal) for r in rows if r.signal.startswith("SIG_GEOM")]
