"""`rei watch`: a run's monitor live, in the terminal and/or in Foxglove.

`rei watch --replay TRACE` plays a recorded run (trace.jsonl or recording.mcap) at
``--speed`` times real time through the same automata and evaluator as `rei replay`, and
shows it (rei.runtime.presentation.live): full-screen on a terminal, one line per signal into a pipe
(or with --plain), and with --foxglove PORT on a Foxglove WebSocket server. `rei watch --bus
ENDPOINT` does the same with the run a simulation publishes on the bus, live. It only reads:
it never sends anything to a run. Exit status:
the watched run's verdict as `rei replay` gives it (0 pass, 1 fail or inconclusive, 2
invalid input, 3 a monitor or recorded run error, 130 interrupted or quit before the end).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import textwrap
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from rei.lang.cli_support import EXIT_BAD_INPUT, EXIT_INTERRUPTED, EXIT_RUN_ERROR
from rei.lang.errors import printable_lines
from rei.lang.vepl_parameters import add_functions_option, add_parameter_option, parameter_values
from rei.runtime.commands.robot import add_bus_options

EXAMPLES = """\
examples:
  rei run examples/navigation/navigation.mission -o out/nav --record
  rei watch --replay out/nav/trace.jsonl                     # full screen, real time (q quits)
  rei watch --replay out/nav/recording.mcap --speed 10       # ten times faster
  rei watch --replay out/nav/trace.jsonl --foxglove 8765 --wait
        # then in Foxglove: Open connection > Foxglove WebSocket > ws://127.0.0.1:8765
  rei watch --replay out/nav/trace.jsonl --speed 0 --plain   # signals as lines, at once
  rei watch --bus tcp/127.0.0.1:7447 --credentials ~/.rei/bus  # the next run on the bus
"""


def _speed(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, found {text!r}") from None
    if not 0 <= value < float("inf"):
        raise argparse.ArgumentTypeError(f"expected a finite number >= 0, found {text!r}")
    return value


def _port(text: str) -> int:
    if not text.isdigit() or not 0 <= int(text) <= 65535:
        raise argparse.ArgumentTypeError(f"expected a port number 0-65535, found {text!r}")
    return int(text)


SETTLE = 0.5
"""Wall seconds without a new subscription after which a client counts as subscribed: a
Foxglove client subscribes to what its panels show in one burst when it connects."""


class SubscriptionBurst:
    """``rei watch --wait``: has a client subscribed, and has its burst of subscriptions
    ended? (Told from the server's thread.)"""

    def __init__(self, clock: Callable[[], float] = time.monotonic) -> None:
        self.clock = clock
        self._last: float | None = None
        self._lock = threading.Lock()

    def add(self, topic: str) -> None:
        with self._lock:
            self._last = self.clock()

    def settled(self) -> bool:
        with self._lock:
            return self._last is not None and self.clock() - self._last >= SETTLE


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = sub.add_parser(
        "watch", help="watch a run live: objects FAR/CLOSE/COLLISION, task, signals, "
                      "utility (terminal, Foxglove)",
        description=textwrap.fill(
                    "Watch a run, recorded (--replay TRACE) or live on the bus (--bus URL, "
                    "as a viewer), as the thesis's monitor showed it: each watched object's "
                    "FAR / CLOSE / COLLISION state, the current task, the latest signals, the "
                    "total utility and the simulated-time factor, judged by the same event "
                    "automata as `rei run` (the default .vepl unless --vepl). On a terminal the "
                    "view is full-screen (q quits); into a pipe, or with --plain, it prints one "
                    "line per signal. --foxglove serves the run to Foxglove on 127.0.0.1, on the "
                    "channels of `rei run --record`'s recording.mcap. Exit status: the watched "
                    "run's verdict (0 pass, 1 fail or inconclusive, 2 invalid input, 3 a monitor "
                    "or recorded run error, or a server that cannot start, 130 interrupted or "
                    "quit before the end).", 88),
        epilog=EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--replay", type=Path, metavar="TRACE",
                        help="a recorded run: trace.jsonl, or recording.mcap of `rei run "
                             "--record`")
    # the same --bus and --credentials as every component that joins a bus (as a viewer,
    # live; needs the 'bus' extra)
    add_bus_options(parser, required=False)
    parser.add_argument("--speed", type=_speed, default=1.0, metavar="F",
                        help="play the recording F times faster than it ran (default 1: "
                             "real time; 0: as fast as it is read)")
    parser.add_argument("--vepl", type=Path, default=None, metavar="FILE",
                        help="the specification that judges the run (default: REI's "
                             "default.vepl); objects' states need its queries "
                             "findCloseToObject and findCollisionToObject")
    add_parameter_option(parser)
    add_functions_option(parser)
    parser.add_argument("--foxglove", type=_port, default=None, metavar="PORT",
                        help="also serve the run to Foxglove (WebSocket on 127.0.0.1:PORT; 0 "
                             "picks a free port, printed on stderr); needs the 'watch' extra")
    parser.add_argument("--wait", action="store_true",
                        help="with --foxglove: start playing when a Foxglove client has "
                             "subscribed (its burst of subscriptions settled for 0.5 s)")
    parser.add_argument("--plain", action="store_true",
                        help="one line per signal instead of the full-screen view")
    parser.add_argument("--exit", action="store_true",
                        help="end when the stream ends (by default a terminal view, or the "
                             "Foxglove server, stays until q or Ctrl-C)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from rei.runtime.observation.errors import MonitorError  # noqa: PLC0415
    from rei.runtime.presentation.live.frames import WatchError  # noqa: PLC0415

    if (args.replay is None) == (args.bus is None):
        print("rei watch: error: expected a stream to watch: --replay TRACE or --bus URL "
              "(one of them), found " + ("both" if args.replay is not None else "neither"),
              file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.wait and args.foxglove is None:
        print("rei watch: error: --wait waits for a Foxglove client: give --foxglove PORT too",
              file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        return _watch(args)
    except WatchError as exc:
        print(f"rei watch: error: {printable_lines(str(exc))}", file=sys.stderr)
        return EXIT_RUN_ERROR
    except MonitorError as exc:
        print(f"rei watch: error: {printable_lines(str(exc))}", file=sys.stderr)
        return EXIT_RUN_ERROR


def _watch(args: argparse.Namespace) -> int:
    from rei.runtime.commands.run import verdict_lines  # noqa: PLC0415
    from rei.runtime.observation.monitor.functions import load_functions  # noqa: PLC0415
    from rei.runtime.presentation.live.foxglove import FoxgloveView  # noqa: PLC0415
    from rei.runtime.presentation.live.frames import StreamSource, View, Watcher  # noqa: PLC0415
    from rei.runtime.presentation.live.sources import BusSource, RecordedSource  # noqa: PLC0415
    from rei.runtime.presentation.live.terminal import Keys, LineView, TerminalView  # noqa: PLC0415
    from rei.runtime.results import judge  # noqa: PLC0415
    from rei.runtime.runs.session import exit_code  # noqa: PLC0415

    if args.replay is not None and not args.replay.is_file():
        print(f"rei watch: error: {args.replay}: expected a trace.jsonl or recording.mcap "
              f"file, found {'a folder' if args.replay.is_dir() else 'nothing'}",
              file=sys.stderr)
        return EXIT_BAD_INPUT
    user = load_functions(args.functions, args.vepl)
    if args.param:  # every name declared, every rule kept: before any view opens
        from rei.lang.vepl.document import load_vepl  # noqa: PLC0415

        load_vepl(args.vepl, parameter_values(args.param))
    full_screen = not args.plain and sys.stdout.isatty()
    screen = TerminalView() if full_screen else None
    views: list[View] = [screen if screen is not None else LineView()]
    subscriptions = SubscriptionBurst()
    foxglove = None
    if args.foxglove is not None:
        foxglove = FoxgloveView(args.foxglove, on_subscribe=subscriptions.add)
        foxglove.serve()
        print(f"rei watch: Foxglove server at {foxglove.url} (Foxglove: Open connection > "
              f"Foxglove WebSocket)", file=sys.stderr, flush=True)
        views.append(foxglove)
    quit_keys = "qQ"
    summary: Any = None
    try:
        with Keys() as keys, tempfile.TemporaryDirectory(prefix="rei-watch-") as work:
            if args.wait:
                print("rei watch: waiting for a Foxglove client to subscribe", file=sys.stderr,
                      flush=True)
                while not subscriptions.settled():
                    if any(k in quit_keys for k in keys.pressed(0.05)):
                        return EXIT_INTERRUPTED
            def quit_pressed() -> bool:
                return any(k in quit_keys for k in keys.pressed())

            source: StreamSource = RecordedSource(args.replay, args.speed) \
                if args.replay is not None else BusSource(args.bus, args.credentials)
            if args.bus is not None:
                print(f"rei watch: waiting for a run on the bus at {args.bus}",
                      file=sys.stderr, flush=True)
            watcher = Watcher(views, args.vepl, Path(work), functions=user,
                              parameters=parameter_values(args.param))
            summary = watcher.watch(source, stop=quit_pressed)
            interactive = screen is not None or foxglove is not None
            if interactive and not args.exit and summary.reason != "stopped watching":
                try:  # the run is judged: Ctrl-C here only ends the holding
                    while not any(k in quit_keys for k in keys.pressed(0.2)):
                        pass
                except KeyboardInterrupt:
                    pass
    except KeyboardInterrupt:
        return EXIT_INTERRUPTED
    finally:
        if screen is not None:
            screen.leave()
        if foxglove is not None:
            foxglove.stop()
    bus = summary.measurements.get("bus", {})
    if bus.get("missed") or bus.get("duplicated") or bus.get("reordered"):
        print(f"rei watch: missed {bus['missed']} sample(s) {bus['missed_samples']}, "
              f"{bus['duplicated']} duplicated, {bus['reordered']} reordered",
              file=sys.stderr)
    for line in verdict_lines(summary, verbose=False):
        print(printable_lines(line))
    verdict = judge(summary)
    print(printable_lines(f"watched {summary.mission}: {summary.outcome} ({summary.reason}); "
                          f"verdict: {verdict.upper()}; total utility "
                          f"{summary.total_utility:g}"))
    return exit_code(summary)
