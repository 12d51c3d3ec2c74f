"""`rei monitor --bus URL -o DIR`: monitor and judge a run elsewhere, live, from the bus.

Joins the bus as the monitor, reads the run's trace as `rei run --bus` publishes it
(``rei.runtime.bus.reception``), feeds it through the same generated automata and evaluator
as `rei run` and `rei replay`, and writes DIR/trace.jsonl (the lines received: byte for
byte the run's; a stream with a gap is kept as trace.jsonl.partial), events.csv,
summary.json (with a ``bus`` measurement: samples received, missed — by sequence number —,
duplicated, reordered, malformed) and report.html. Exit status: 0 every requirement passed,
1 one failed or was inconclusive (a sample missed makes the requirements it was evidence
for inconclusive), 2 invalid input, 3 a monitor error or a recorded run error, 130
interrupted.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from rei.lang.cli_support import EXIT_BAD_INPUT, EXIT_RUN_ERROR
from rei.lang.errors import printable_lines
from rei.lang.vepl_parameters import add_functions_option, add_parameter_option, parameter_values
from rei.runtime.commands.robot import add_bus_options, join_bus
from rei.runtime.commands.run import REPLAY_VERBOSE_HELP, add_verbosity, print_results, write_page
from rei.runtime.runs.session import EVENTS, TRACE

EXAMPLES = """\
examples:
  rei monitor --bus tcp/127.0.0.1:7447 -o out/watched
  rei monitor --bus tcp/127.0.0.1:7447 -o out/safety --vepl examples/navigation/human_safety.vepl
"""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = sub.add_parser(
        "monitor", help="monitor and judge a distributed run from the bus",
        description="Join the bus as the monitor, read the trace of the next run `rei run "
                    "--bus` publishes, judge it with the event automata of a .vepl (the "
                    "default one unless --vepl) and write trace.jsonl, events.csv, "
                    "summary.json and report.html into the output folder: the same events "
                    "and verdicts as the run's own monitor. Samples lost on the way are "
                    "named by sequence number in summary.json and make the requirements "
                    "they were evidence for inconclusive, never pass. See docs/bus.md.",
        epilog=EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_bus_options(parser)
    parser.add_argument("-o", "--output", type=Path, required=True, metavar="DIR",
                        help="output folder (created if missing)")
    parser.add_argument("--vepl", type=Path, default=None, metavar="FILE",
                        help="the specification (default: REI's default.vepl)")
    add_parameter_option(parser)
    add_functions_option(parser)
    parser.add_argument("--silence", type=float, default=60.0, metavar="S",
                        help="wall seconds without a sample after which the run counts as "
                             "cut off (default 60)")
    add_verbosity(parser, REPLAY_VERBOSE_HELP)
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from rei.generators.output import open_output  # noqa: PLC0415
    from rei.runtime.bus import BusError  # noqa: PLC0415
    from rei.runtime.bus.reception import TraceStream, ask_header  # noqa: PLC0415
    from rei.runtime.bus.schema import TRACE as TRACE_KEY  # noqa: PLC0415
    from rei.runtime.bus.schema import config_key  # noqa: PLC0415
    from rei.runtime.observation.errors import MonitorError  # noqa: PLC0415
    from rei.runtime.observation.judgement import judge_stream  # noqa: PLC0415
    from rei.runtime.observation.monitor import generate_automata  # noqa: PLC0415
    from rei.runtime.observation.monitor.functions import load_functions  # noqa: PLC0415

    if not (math.isfinite(args.silence) and args.silence > 0):
        print(f"rei monitor: error: --silence: expected a positive number of seconds, found "
              f"{args.silence}", file=sys.stderr)
        return EXIT_BAD_INPUT
    parameters = parameter_values(args.param)
    if parameters:  # every name declared, every rule kept: before the outputs are touched
        from rei.lang.vepl.document import load_vepl  # noqa: PLC0415

        load_vepl(args.vepl, parameters)
    out: Path = args.output
    out.mkdir(parents=True, exist_ok=True)
    automata = generate_automata(args.vepl, out / "automata", replace=True,
                                 parameters=parameters)
    user = load_functions(args.functions, args.vepl)
    # the inputs are good: an earlier judgement in the folder goes now, not before
    for stale in ("summary.json", TRACE, TRACE + ".partial", EVENTS, "report.html"):
        (out / stale).unlink(missing_ok=True)
    session = join_bus(args, "monitor")
    if isinstance(session, int):
        return session
    with session:
        stream = TraceStream(ask_header(session.call, config_key("trace"), 10.0),
                             args.silence)
        session.subscribe_raw(TRACE_KEY, stream.receive)
        if not args.quiet:
            print(f"rei monitor: waiting for a run on {session.endpoint}", file=sys.stderr,
                  flush=True)
        try:
            header = stream.header()
        except BusError as exc:
            print(f"rei monitor: error: {exc}", file=sys.stderr)
            return EXIT_RUN_ERROR
        if not args.quiet:
            print(f"rei monitor: judging {header.mission} in {header.world}, seed "
                  f"{header.seed}", file=sys.stderr, flush=True)
        try:
            summary = judge_stream(header, stream.samples(), stream.read_end, args.vepl, out,
                                   user, automata, f"the run on {session.endpoint}",
                                   controller="bus", parameters=parameters,
                                   measurements=lambda: {
                                       "bus": {**stream.measurements(),
                                               "dropped": session.dropped}})
        except MonitorError as exc:
            print(f"rei monitor: error: {printable_lines(str(exc))}", file=sys.stderr)
            return EXIT_RUN_ERROR
    # The lines judged are trace.jsonl's own bytes; a stream with a gap is no trace (its
    # rows are changes): kept as trace.jsonl.partial, as a run cut short leaves its own.
    whole = not stream.missed and stream.end is not None
    trace = out / (TRACE if whole else TRACE + ".partial")
    with open_output(trace) as file:
        file.write("".join(line.decode("utf-8") + "\n" for line in stream.lines))
    bus = summary.measurements.get("bus", {})
    if bus.get("missed") or bus.get("duplicated") or bus.get("reordered"):
        print(f"rei monitor: missed {bus['missed']} sample(s) {bus['missed_samples']}, "
              f"{bus['duplicated']} duplicated, {bus['reordered']} reordered",
              file=sys.stderr)
    page = write_page(out, trace if whole else None)
    return print_results(summary, out, page=page, quiet=args.quiet, verbose=args.verbose)
