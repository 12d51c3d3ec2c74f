"""`rei replay TRACE --vepl FILE -o DIR`: monitor a recorded trace offline.

TRACE is a trace.jsonl or an MCAP recording (`rei run --record`'s recording.mcap, read
through its /rei/trace channel with the trace's own rules; a recording cut short by a crash
is replayed up to its last complete chunk, as an interrupted run). The trace's samples go
through the same generated automata and evaluator as a live run, so
the event log and verdicts equal the live run's (same trace, same specification). Writes
DIR/events.csv, DIR/summary.json, DIR/automata/automata.py and DIR/report.html (the run's
page, drawn from the trace; its map needs the run's world/ folder beside the trace). Prints
the results on stdout as `rei run` does (``print_results``: the same lines, --quiet and
--verbose), diagnostics on stderr. Exit status: 0 every requirement passed, 1 one failed or
was inconclusive, 2 invalid input (a bad .vepl, an unreadable trace, or a .vepl whose queries
read data the trace does not carry: VEPL-DATA), 3 a monitor error or a recorded run error, 130
a recorded interrupted run.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, cast

from rei.lang.cli_support import EXIT_RUN_ERROR
from rei.lang.errors import printable_lines
from rei.runtime.commands.run import (
    REPLAY_VERBOSE_HELP,
    add_verbosity,
    print_results,
    write_page,
)
from rei.runtime.messages import Sample, StreamHeader
from rei.runtime.results import RESULTS_VERSION, Outcome, RunSummary

HELP_EXAMPLES = """\
rei replay out/nav/trace.jsonl -o out/nav-strict --vepl examples/navigation/human_safety.vepl
rei replay out/rec/recording.mcap -o out/rec-again -v     # every requirement, with reasons
"""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = sub.add_parser(
        "replay", help="monitor a recorded trace (or recording.mcap) with the event automata "
                       "of a .vepl file",
        description="Feed a trace recorded by `rei run` (trace.jsonl, or the recording.mcap "
                    "of `rei run --record`) through the event automata generated from a .vepl "
                    "specification (the default one unless --vepl) and write events.csv, "
                    "summary.json and report.html (the run's page). Same trace and "
                    "specification give the same events and verdicts as the live run. A "
                    "recording cut short by a crash is replayed up to its last complete chunk "
                    "and judged as an interrupted run. Results go to stdout, diagnostics to "
                    "stderr. Exit status: 0 every requirement passed, 1 one failed or was "
                    "inconclusive (or the .vepl declares no requirement: verdict UNJUDGED, "
                    "never a pass), 2 invalid input (a bad .vepl, an unreadable trace, a .vepl "
                    "reading data the trace lacks), 3 a monitor error or a recorded run error, "
                    "130 a recorded interrupted run.")
    parser.add_argument("trace", type=Path, metavar="TRACE",
                        help="a trace.jsonl file or an MCAP recording (.mcap)")
    parser.add_argument("--vepl", type=Path, default=None, metavar="FILE",
                        help="the specification (default: REI's default.vepl); its queries "
                             "may read only the data the trace carries (its header's "
                             "\"data\"), else exit 2")
    parser.add_argument("--functions", default=None, metavar="MODULE",
                        help="Python module (dotted name or .py file) defining the user "
                             "functions the specification declares with 'function'")
    parser.add_argument("-o", "--output", type=Path, required=True, metavar="DIR",
                        help="output folder (created if missing)")
    add_verbosity(parser, REPLAY_VERBOSE_HELP)
    parser.set_defaults(func=run)


def replay(trace: Path, vepl: Path | None, out_dir: Path,
           functions: str | None = None) -> RunSummary:
    """Monitor ``trace`` into ``out_dir``; the summary (also written as summary.json)."""
    from rei.runtime.monitor import generate_automata  # noqa: PLC0415
    from rei.runtime.monitor.functions import load_functions  # noqa: PLC0415
    from rei.runtime.recording import read_stream  # noqa: PLC0415

    # The specification is checked and generated before the trace is opened: a bad .vepl
    # is reported without touching the trace.
    automata = generate_automata(vepl, Path(out_dir) / "automata", replace=True)
    user = load_functions(functions, vepl)
    header, samples, read_end = read_stream(trace)
    return judge_stream(header, samples, read_end, vepl, out_dir, user, automata,
                        f"the trace '{trace}'")


def judge_stream(header: StreamHeader, samples: Iterator[Sample],
                 read_end: Callable[[], tuple[float, str, str] | None], vepl: Path | None,
                 out_dir: Path, user: Any, automata: Any, source: str,
                 controller: str = "replay",
                 measurements: Callable[[], dict[str, Any]] | None = None,
                 judged: Callable[[Any, Sample], None] | None = None) -> RunSummary:
    """Monitor a stream (``replay``'s trace, `rei monitor`'s bus) into ``out_dir``; the
    summary (also written as summary.json). ``source`` names the stream in errors;
    ``measurements`` gives more of the summary's measurements once the stream ended;
    ``judged(sink, sample)`` is told of each sample once the monitor has judged it (`rei
    watch` shows it)."""
    from rei.lang.vepl.document import load_vepl  # noqa: PLC0415
    from rei.runtime.collector.needs import check_needs  # noqa: PLC0415
    from rei.runtime.evaluator.summary import merge_summary, write_summary  # noqa: PLC0415
    from rei.runtime.faults.stage import SampledTimeline, fault_measurements  # noqa: PLC0415
    from rei.runtime.monitor import MonitorSink  # noqa: PLC0415

    try:
        # Never judge on data the recording does not carry (a false PASS): refuse first.
        check_needs(load_vepl(vepl), header.data, f"{source} to carry",
                    "record it again with a mission whose monitor block collects that data, or "
                    "drop the query")
    except BaseException:
        close = getattr(samples, "close", None)
        if close is not None:
            close()
        raise
    sink = MonitorSink(vepl, out_dir, functions=user, automata=automata)
    last = 0.0
    seen = SampledTimeline()
    try:
        sink.start(header)
        for sample in samples:
            sink.feed(sample)
            last = sample.time
            if header.faults:
                seen.feed(sample.time, sample.faults)
            if judged is not None:
                judged(sink, sample)
    finally:
        close = getattr(samples, "close", None)
        if close is not None:
            close()
    end = read_end()
    cut = getattr(samples, "cut_short", "")
    end_time, outcome, reason = end if end is not None else (
        last, "interrupted", cut or "the trace has no end line")
    sink.finish(end_time, outcome, reason)
    assert sink.result is not None
    # The end line was written by `rei run` from its summary's outcome; read back as is.
    base = RunSummary(RESULTS_VERSION, header.mission, header.world, header.seed, controller,
                      cast(Outcome, outcome), reason, sink.result.duration, 0.0, {}, (),
                      {**fault_measurements(header.faults, seen.timeline()),
                       **(measurements() if measurements is not None else {})})
    summary = merge_summary(base, sink.result)
    write_summary(summary, out_dir)
    return summary


def run(args: argparse.Namespace) -> int:
    from rei.runtime.monitor.errors import MonitorError  # noqa: PLC0415

    try:
        summary = replay(args.trace, args.vepl, args.output, args.functions)
    except MonitorError as exc:
        print(f"rei replay: error: {printable_lines(str(exc))}", file=sys.stderr)
        return EXIT_RUN_ERROR
    page = write_page(args.output, args.trace)
    # the one pass rule of `rei run`; a recorded run error stays an error
    return print_results(summary, args.output, page=page, quiet=args.quiet,
                         verbose=args.verbose)
