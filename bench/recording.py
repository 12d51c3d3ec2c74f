"""Benchmark of recordings: replay speed from MCAP, and what `rei run --record` costs.

Replay: a one-hour stream at 10 Hz (36,000 samples; a robot driving a zig-zag among boxes,
walls and humans, a 360-beam scan every other sample, as bench/monitor.py builds it) is
written once through ``McapRecorder`` (recording.mcap) and once through ``TraceWriter``
(trace.jsonl), then replayed from each with ``rei replay``'s own function (the default
specification: generate the automata, read and check every record, monitor, write
events.csv and summary.json). Reported: wall and CPU seconds, recorded samples per wall
second, and whether the two replays wrote the same events.csv. Target: under 10 s from MCAP.

Recording cost: the same real mission run twice in this process (``run_into``, reference
navigator, seed 0), without and with the recorder sink; the real-time factors of the loop
(simulated seconds per wall second, and per CPU second) and the slowdown. Best of
``--repeat`` runs each (the machine is shared). Also: the recorder alone on the synthetic
stream (microseconds per sample) and the file sizes. Target: recording costs under 15 %.

Usage: python bench/recording.py [--samples N] [--mission FILE] [--repeat K] [--out DIR]
Figures are never asserted by tests.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench.monitor import scenario  # noqa: E402
from rei.runtime.commands.replay import replay  # noqa: E402
from rei.runtime.messages import Sample, StreamHeader  # noqa: E402
from rei.runtime.observation import recordings as recording  # noqa: E402
from rei.runtime.observation.recordings import McapRecorder  # noqa: E402
from rei.runtime.runs.session import run_into  # noqa: E402
from rei.runtime.trace import TraceWriter  # noqa: E402

MISSION = ROOT / "examples" / "small_dense" / "small_dense.mission"


def _clock() -> tuple[float, float]:
    return time.perf_counter(), time.process_time()


def _since(start: tuple[float, float]) -> tuple[float, float]:
    wall, cpu = _clock()
    return wall - start[0], cpu - start[1]


def replay_speed(n_samples: int, work: Path) -> None:
    header, samples = scenario(30, n_samples)
    end = samples[-1].time
    mcap, trace = work / "recording.mcap", work / "trace.jsonl"
    timings = {}
    for name in ("trace writer alone", "recorder alone", "trace writer + recorder (a run)"):
        writer = TraceWriter(work / "t.jsonl") if "recorder" in name else TraceWriter(trace)
        sinks: list[TraceWriter | McapRecorder] = [] if name == "recorder alone" else [writer]
        if "recorder" in name:
            sinks.append(McapRecorder(mcap, trace=writer if sinks else None))
        start = _clock()
        for sink in sinks:
            sink.start(header)
        for s in samples:
            for sink in sinks:
                sink.feed(s)
        for sink in sinks:
            sink.finish(end, "completed", "")
        timings[name] = _since(start)
    print(f"stream: {n_samples} samples ({end:.0f} s at 10 Hz), 30 objects, 360-beam scans "
          f"every other sample")
    for name, (wall, cpu) in timings.items():
        print(f"  writing it through the {name}: {wall:.2f} s wall, {cpu:.2f} s CPU, "
              f"{1e6 * cpu / n_samples:.0f} µs CPU per sample")
    print(f"  sizes: recording.mcap {mcap.stat().st_size / 1e6:.1f} MB, trace.jsonl "
          f"{trace.stat().st_size / 1e6:.1f} MB")
    results = {}
    for name, path in (("MCAP", mcap), ("JSON lines", trace)):
        start = _clock()
        summary = replay(path, None, work / f"replay_{name.replace(' ', '_')}")
        wall, cpu = _since(start)
        results[name] = (work / f"replay_{name.replace(' ', '_')}" / "events.csv").read_bytes()
        print(f"  replay from {name}: {wall:.2f} s wall, {cpu:.2f} s CPU, "
              f"{n_samples / wall:,.0f} samples/s ({summary.verdict}, "
              f"{sum(summary.signal_counts.values())} signals)")
    print(f"  same events.csv from both: {results['MCAP'] == results['JSON lines']}")


class _TimedRecorder(McapRecorder):
    """The recorder, timing its own calls (CPU seconds) inside the run."""

    cpu = 0.0
    """Class-level total of the latest run (the bench's own bookkeeping)."""

    def start(self, header: StreamHeader) -> None:
        t = time.process_time()
        super().start(header)
        _TimedRecorder.cpu += time.process_time() - t

    def feed(self, sample: Sample) -> None:
        t = time.process_time()
        super().feed(sample)
        _TimedRecorder.cpu += time.process_time() - t

    def finish(self, end_time: float, outcome: str, reason: str) -> None:
        t = time.process_time()
        super().finish(end_time, outcome, reason)
        _TimedRecorder.cpu += time.process_time() - t


def recording_cost(mission: Path, repeat: int, work: Path) -> None:
    best: dict[bool, tuple[float, float, float, float]] = {}
    shares: list[float] = []
    duration = 0.0
    recording.McapRecorder = _TimedRecorder  # type: ignore[misc]  # what run_into builds
    for k in range(repeat):
        for record in (False, True):
            _TimedRecorder.cpu = 0.0
            start = _clock()
            summary, run = run_into(mission, work / f"run_{record}_{k}", recording=record)
            whole = _since(start)
            if record:
                shares.append(_TimedRecorder.cpu / run.cpu_seconds)
            duration = summary.duration
            loop = (duration / run.wall_seconds, duration / run.cpu_seconds)
            # best of the repeats, each figure on its own (the machine is shared)
            old = best.get(record, (0.0, 0.0, math.inf, math.inf))
            best[record] = (max(old[0], loop[0]), max(old[1], loop[1]),
                            min(old[2], whole[0]), min(old[3], whole[1]))
    plain, rec = best[False], best[True]
    size = (work / "run_True_0" / "recording.mcap").stat().st_size
    trace = (work / "run_True_0" / "trace.jsonl").stat().st_size
    print(f"mission {mission.name}: {duration:.1f} s simulated, best of {repeat}")
    for name, b in (("without --record", plain), ("with --record", rec)):
        print(f"  {name}: loop {b[0]:.0f}x real time ({b[1]:.0f}x per CPU second); whole "
              f"run_into (generation, set-up, outputs) {b[2]:.2f} s wall, {b[3]:.2f} s CPU")
    print(f"  cost of recording: loop {100 * (plain[0] / rec[0] - 1):.1f} % wall, "
          f"{100 * (plain[1] / rec[1] - 1):.1f} % CPU; whole run "
          f"{100 * (rec[2] / plain[2] - 1):.1f} % wall, {100 * (rec[3] / plain[3] - 1):.1f} % "
          f"CPU; recording.mcap {size / 1e3:.0f} kB (trace.jsonl {trace / 1e3:.0f} kB)")
    print(f"  the recorder's own calls, timed inside the runs: {100 * min(shares):.1f}-"
          f"{100 * max(shares):.1f} % of the loop's CPU time "
          f"({1e6 * _TimedRecorder.cpu / (10 * duration):.0f} µs per sample at 10 Hz)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=int, default=36_000)
    parser.add_argument("--mission", type=Path, default=MISSION)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        work = args.out or Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        replay_speed(args.samples, work)
        recording_cost(args.mission, args.repeat, work)


if __name__ == "__main__":
    main()
