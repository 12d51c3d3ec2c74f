"""`rei replay TRACE --vepl FILE -o DIR`: monitor a recorded trace offline.

The trace's samples go through the same generated automata and evaluator as a live run, so
the event log and verdicts equal the live run's (same trace, same specification). Writes
DIR/events.csv, DIR/summary.json, DIR/automata/automata.py and DIR/report.html (the run's
page, drawn from the trace; its map needs the run's world/ folder beside the trace). Exit
status: 0 every requirement passed, 1 one failed or was inconclusive, 2 invalid input (a bad
.vepl or an unreadable trace), 3 a monitor error.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import cast

from rei.lang.cli_support import EXIT_RUN_ERROR
from rei.runtime.collector.trace import read_trace, read_trace_end
from rei.runtime.commands.run import write_page
from rei.runtime.evaluator.summary import merge_summary, write_summary
from rei.runtime.monitor import MonitorSink, generate_automata
from rei.runtime.monitor.errors import MonitorError
from rei.runtime.monitor.functions import load_functions
from rei.runtime.results import RESULTS_VERSION, Outcome, RunSummary, judge


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = sub.add_parser(
        "replay", help="monitor a recorded trace with the event automata of a .vepl file",
        description="Feed a trace recorded by `rei run` through the event automata generated "
                    "from a .vepl specification (the default one unless --vepl) and write "
                    "events.csv, summary.json and report.html (the run's page). Same trace "
                    "and specification give the same events and verdicts as the live run.")
    parser.add_argument("trace", type=Path, metavar="TRACE", help="a trace.jsonl file")
    parser.add_argument("--vepl", type=Path, default=None, metavar="FILE",
                        help="the specification (default: REI's default.vepl)")
    parser.add_argument("--functions", default=None, metavar="MODULE",
                        help="Python module (dotted name or .py file) defining the user "
                             "functions the specification declares with 'function'")
    parser.add_argument("-o", "--output", type=Path, required=True, metavar="DIR",
                        help="output folder (created if missing)")
    parser.set_defaults(func=run)


def replay(trace: Path, vepl: Path | None, out_dir: Path,
           functions: str | None = None) -> RunSummary:
    """Monitor ``trace`` into ``out_dir``; the summary (also written as summary.json)."""
    # The specification is checked and generated before the trace is opened: a bad .vepl
    # is reported without touching the trace.
    automata = generate_automata(vepl, Path(out_dir) / "automata", replace=True)
    user = load_functions(functions, vepl)
    header, samples = read_trace(trace)
    sink = MonitorSink(vepl, out_dir, functions=user, automata=automata)
    last = 0.0
    try:
        sink.start(header)
        for sample in samples:
            sink.feed(sample)
            last = sample.time
    finally:
        close = getattr(samples, "close", None)
        if close is not None:
            close()
    end = read_trace_end(trace)
    end_time, outcome, reason = end if end is not None else (last, "interrupted",
                                                             "the trace has no end line")
    sink.finish(end_time, outcome, reason)
    assert sink.result is not None
    # The end line was written by `rei run` from its summary's outcome; read back as is.
    base = RunSummary(RESULTS_VERSION, header.mission, header.world, header.seed, "replay",
                      cast(Outcome, outcome), reason, sink.result.duration, 0.0, {}, ())
    summary = merge_summary(base, sink.result)
    write_summary(summary, out_dir)
    return summary


def run(args: argparse.Namespace) -> int:
    try:
        summary = replay(args.trace, args.vepl, args.output, args.functions)
    except MonitorError as exc:
        print(f"rei replay: error: {exc}", file=sys.stderr)
        return EXIT_RUN_ERROR
    for v in summary.verdicts:
        print(f"{v.requirement}: {v.status.replace('_', ' ')} ({v.reason})")
    write_page(args.output, args.trace)
    verdict = judge(summary)
    print(f"verdict: {verdict.upper()}; total utility {summary.total_utility:g}; wrote "
          f"{args.output / 'events.csv'}")
    # the one pass rule of `rei run`; a recorded run error stays an error
    return 0 if verdict == "pass" else EXIT_RUN_ERROR if verdict == "error" else 1
