"""The one stream judgement: a run's sample stream (a live run's sink, `rei replay`'s trace,
`rei monitor`'s bus, a ROS 2 bag, `rei watch`'s source) through the generated automata and
the evaluator into events.csv and summary.json.

Every consumer that judges a stream calls ``judge_stream``, so a replayed trace, a monitored
bus and a watched recording are judged alike. It reads the stream it is given and never
imports pybullet, the simulation loop or the command line.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

from rei.lang.vepl_parameters import ParameterValues
from rei.runtime.results import RESULTS_VERSION, Outcome, RunSummary

if TYPE_CHECKING:
    from rei.runtime.messages import Sample, StreamHeader
    from rei.runtime.trace import TraceWriter


def judge_stream(header: StreamHeader, samples: Iterator[Sample],
                 read_end: Callable[[], tuple[float, str, str] | None], vepl: Path | None,
                 out_dir: Path, user: Any, automata: Any, source: str,
                 controller: str = "replay",
                 measurements: Callable[[], dict[str, Any]] | None = None,
                 judged: Callable[[Any, Sample], None] | None = None,
                 trace: TraceWriter | None = None,
                 parameters: ParameterValues = ()) -> RunSummary:
    """Monitor a stream (``replay``'s trace, `rei monitor`'s bus) into ``out_dir``; the
    summary (also written as summary.json). ``source`` names the stream in errors;
    ``measurements`` gives more of the summary's measurements once the stream ended;
    ``judged(sink, sample)`` is told of each sample once the monitor has judged it (`rei
    watch` shows it); ``trace``, when given, gets a copy of the stream (a trace that cannot be
    written is dropped, never the judgement). A stream with ``problems`` (a ROS 2 bag's bad
    data) has every verdict that would pass made inconclusive. ``parameters`` (`--param`)
    replace the specification's values; those other than the file's are in the summary."""
    from rei.lang.vepl.document import changed_parameters, load_vepl  # noqa: PLC0415
    from rei.runtime.observation.evaluator.summary import (  # noqa: PLC0415
        merge_summary,
        write_summary,
    )
    from rei.runtime.observation.monitor import MonitorSink  # noqa: PLC0415
    from rei.runtime.observation.monitor.needs import check_needs  # noqa: PLC0415
    from rei.runtime.simulation.faults.stage import (  # noqa: PLC0415
        SampledTimeline,
        fault_measurements,
    )

    try:
        # Never judge on data the recording does not carry (a false PASS): refuse first.
        check_needs(load_vepl(vepl, parameters), header.data, f"{source} to carry",
                    "record it again with a mission whose monitor block collects that data, or "
                    "drop the query")
    except BaseException:
        close = getattr(samples, "close", None)
        if close is not None:
            close()
        raise
    changed = changed_parameters(vepl, parameters)
    sink = MonitorSink(vepl, out_dir, functions=user, automata=automata, parameters=parameters)
    last = 0.0
    seen = SampledTimeline()
    copy = _TraceCopy(trace)
    try:
        sink.start(header)
        copy.start(header)
        for sample in samples:
            sink.feed(sample)
            copy.feed(sample)
            last = sample.time
            if header.faults:
                seen.feed(sample.time, sample.faults)
            if judged is not None:
                judged(sink, sample)
    except BaseException:
        copy.abandon()
        raise
    finally:
        close = getattr(samples, "close", None)
        if close is not None:
            close()
    try:
        end = read_end()
    except BaseException:
        copy.abandon()
        raise
    cut = getattr(samples, "cut_short", "")
    end_time, outcome, reason = end if end is not None else (
        last, "interrupted", cut or "the trace has no end line")
    sink.finish(end_time, outcome, reason)
    copy.finish(end_time, outcome, reason)
    assert sink.result is not None
    # The end line was written by `rei run` from its summary's outcome; read back as is.
    base = RunSummary(RESULTS_VERSION, header.mission, header.world, header.seed, controller,
                      cast(Outcome, outcome), reason, sink.result.duration, 0.0, {}, (),
                      {**fault_measurements(header.faults, seen.timeline()),
                       **(measurements() if measurements is not None else {})})
    summary = replace(merge_summary(base, sink.result), parameters=dict(changed))
    problems = [p.text() for p in getattr(samples, "problems", ())]  # a bag's bad data
    if problems:
        summary = _doubted(summary, problems)
    write_summary(summary, out_dir)
    return summary


class _TraceCopy:
    """The judged stream copied into a trace.jsonl, as far as the trace's rules take it: a
    sample they refuse (a bag's NaN pose) ends the copy, never the judgement."""

    def __init__(self, writer: TraceWriter | None) -> None:
        self.writer = writer

    def _do(self, write: Callable[[TraceWriter], None]) -> None:
        from rei.runtime.trace import TraceError  # noqa: PLC0415

        if self.writer is None:
            return
        try:
            write(self.writer)
        except TraceError:
            self.abandon()

    def start(self, header: StreamHeader) -> None:
        self._do(lambda w: w.start(header))

    def feed(self, sample: Sample) -> None:
        self._do(lambda w: w.feed(sample))

    def finish(self, end_time: float, outcome: str, reason: str) -> None:
        self._do(lambda w: w.finish(end_time, outcome, reason))

    def abandon(self) -> None:
        if self.writer is not None:
            self.writer.abandon()
        self.writer = None


def _doubted(summary: RunSummary, problems: list[str]) -> RunSummary:
    """Every verdict that passed becomes inconclusive: the data it rests on has gaps,
    stamps going backwards, non-finite values or bad scans (the recording's problems)."""
    first = problems[0]
    more = f" (and {len(problems) - 1} more problem(s), listed in measurements)" \
        if len(problems) > 1 else ""
    verdicts = tuple(replace(v, status="inconclusive",
                             reason=f"the recording's data cannot support a pass: {first}"
                                    f"{more}; {v.reason}")
                     if v.status == "pass" else v for v in summary.verdicts)
    return replace(summary, verdicts=verdicts,
                   measurements={**summary.measurements, "recording_problems": problems[:100],
                                 "recording_problem_count": len(problems)})
